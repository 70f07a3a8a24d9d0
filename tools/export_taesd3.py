#!/usr/bin/env python3
"""Export TAESD3 as TorchScript modules for latentpt's --vae-encoder/--vae-decoder/--vae-config.

latentpt runs TAESD3 natively; this export exists to test the TorchScript path (the one the
SD3.5 VAE takes, tools/export_vae.py) against the native network, and as a small example of the
module contract:
    encoder: [N, 3, H, W] image in `image_range` -> [N, C, H/f, W/f] latent
    decoder: [N, C, h, w] latent -> [N, 3, f*h, f*w] image in `image_range`
with vae.json giving channels, downsample f, scale, shift, image_range and whether latents are
`raw` VAE latents or already in the diffusion `model` space (TAESD3 works in model space).

Needs only Debian's python3-torch (1.13): the BF16 safetensors files are read here directly,
since that torch has no safetensors reader.

usage: python3 tools/export_taesd3.py [--weights ../shared/models/taesd3] --out DIR
"""
import argparse
import json
import os
import struct
import sys

import torch
import torch.nn as nn


def read_safetensors(path):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 8:
        sys.exit(f"{path}: truncated")
    (n,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8:8 + n])
    body = data[8 + n:]
    out = {}
    for name, t in header.items():
        if name == "__metadata__":
            continue
        b, e = t["data_offsets"]
        if t["dtype"] == "BF16":
            raw = torch.frombuffer(bytearray(body[b:e]), dtype=torch.int16).to(torch.int32) << 16
            out[name] = raw.view(torch.float32).reshape(t["shape"]).clone()
        elif t["dtype"] == "F32":
            out[name] = torch.frombuffer(bytearray(body[b:e]), dtype=torch.float32).reshape(t["shape"]).clone()
        else:
            sys.exit(f"{path}: tensor {name}: unsupported dtype {t['dtype']}")
    return out


def conv(cin, cout, stride=1, bias=True):
    return nn.Conv2d(cin, cout, 3, stride=stride, padding=1, bias=bias)


class Block(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.conv = nn.Sequential(conv(c, c), nn.ReLU(), conv(c, c), nn.ReLU(), conv(c, c))

    def forward(self, x):
        return torch.relu(self.conv(x) + x)


class Clamp(nn.Module):
    def forward(self, x):
        return torch.tanh(x / 3) * 3


def encoder(c=16):
    return nn.Sequential(conv(3, 64), Block(64),
                         conv(64, 64, 2, False), Block(64), Block(64), Block(64),
                         conv(64, 64, 2, False), Block(64), Block(64), Block(64),
                         conv(64, 64, 2, False), Block(64), Block(64), Block(64),
                         conv(64, c))


def decoder(c=16):
    return nn.Sequential(Clamp(), conv(c, 64), nn.ReLU(), Block(64), Block(64), Block(64),
                         nn.Upsample(scale_factor=2), conv(64, 64, bias=False), Block(64), Block(64), Block(64),
                         nn.Upsample(scale_factor=2), conv(64, 64, bias=False), Block(64), Block(64), Block(64),
                         nn.Upsample(scale_factor=2), conv(64, 64, bias=False), Block(64),
                         conv(64, 3))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    shared = os.environ.get("LATENTPT_SHARED", os.path.join(here, "..", "..", "shared"))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", default=os.path.join(shared, "models", "taesd3"), help="folder with taesd3_{encoder,decoder}.safetensors")
    ap.add_argument("--out", required=True, help="output folder for encoder.pt, decoder.pt, vae.json")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for name, net in (("encoder", encoder()), ("decoder", decoder())):
        path = os.path.join(a.weights, f"taesd3_{name}.safetensors")
        if not os.path.exists(path):
            sys.exit(f"{path}: not found (pass --weights or set LATENTPT_SHARED)")
        net.load_state_dict(read_safetensors(path), strict=True)
        net.eval()
        scripted = torch.jit.script(net)
        tmp = os.path.join(a.out, f".{name}.pt.tmp")
        scripted.save(tmp)
        os.replace(tmp, os.path.join(a.out, f"{name}.pt"))
    config = {"name": "taesd3 (TorchScript export)", "channels": 16, "downsample": 8, "scale": 1.5305, "shift": 0.0609,
              "image_range": [0, 1], "latent": "model"}
    with open(os.path.join(a.out, "vae.json"), "w") as f:
        json.dump(config, f, indent=2)
    print(f"wrote {a.out}/encoder.pt, decoder.pt, vae.json")


if __name__ == "__main__":
    main()
