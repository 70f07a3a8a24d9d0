#!/usr/bin/env python3
"""Export a diffusers AutoencoderKL (the Stable Diffusion 3.5 VAE by default) as TorchScript for
latentpt: --vae-encoder encoder.pt --vae-decoder decoder.pt --vae-config vae.json.

Needs what latentpt itself does not: `pip install diffusers` and the model weights (SD3.5 is
gated on Hugging Face: accept its licence, then `huggingface-cli login`). Run once; latentpt then
loads the two .pt files with torch::jit::load, no Python involved.

The exported modules follow latentpt's contract (see tools/export_taesd3.py):
    encoder: image in [-1, 1], [N, 3, H, W] -> posterior MEAN, the raw latent [N, 16, H/8, W/8]
    decoder: raw latent -> image in [-1, 1]
and vae.json says `"latent": "raw"` with scale 1.5305 and shift 0.0609, so latentpt maps raw
latents to the diffusion model's space as diffusers does: model = (raw - shift) * scale, and
back before decoding. Images are mapped [0, 1] -> [-1, 1] on the way in and back on the way out.

usage: python3 tools/export_vae.py --out DIR [--model stabilityai/stable-diffusion-3.5-large]
       [--size 256] [--dtype float32]
"""
import argparse
import json
import os
import sys

import torch


class Encoder(torch.nn.Module):
    def __init__(self, vae):
        super().__init__()
        self.encoder = vae.encoder
        self.quant_conv = vae.quant_conv

    def forward(self, x):
        h = self.encoder(x)
        if self.quant_conv is not None:
            h = self.quant_conv(h)
        mean, _logvar = torch.chunk(h, 2, dim=1)  # DiagonalGaussianDistribution(h).mean
        return mean


class Decoder(torch.nn.Module):
    def __init__(self, vae):
        super().__init__()
        self.decoder = vae.decoder
        self.post_quant_conv = vae.post_quant_conv

    def forward(self, z):
        if self.post_quant_conv is not None:
            z = self.post_quant_conv(z)
        return self.decoder(z)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default="stabilityai/stable-diffusion-3.5-large", help="diffusers model id or local folder")
    ap.add_argument("--subfolder", default="vae")
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", type=int, default=256, help="image side used for tracing (the modules run at any multiple of 8)")
    ap.add_argument("--dtype", default="float32", choices=["float32"], help="latentpt runs the VAE in float32 on the CPU")
    a = ap.parse_args()
    try:
        from diffusers import AutoencoderKL
    except ImportError:
        sys.exit("export_vae.py needs diffusers: pip install diffusers (plus the model weights; see --help)")
    vae = AutoencoderKL.from_pretrained(a.model, subfolder=a.subfolder, torch_dtype=torch.float32).eval()
    cfg = vae.config
    channels = int(cfg.latent_channels)
    scale = float(getattr(cfg, "scaling_factor", 1.0) or 1.0)
    shift = float(getattr(cfg, "shift_factor", 0.0) or 0.0)
    downsample = 2 ** (len(cfg.block_out_channels) - 1)
    os.makedirs(a.out, exist_ok=True)
    x = torch.zeros(1, 3, a.size, a.size)
    with torch.no_grad():
        enc = torch.jit.trace(Encoder(vae), x)
        z = enc(x)
        dec = torch.jit.trace(Decoder(vae), z)
        # The traced graphs must reproduce diffusers on a second size (tracing is shape-specialised
        # if some op recorded constant sizes): fail here rather than in latentpt.
        x2 = torch.rand(1, 3, a.size // 2 + 8, a.size // 2) * 2 - 1
        ref = vae.encode(x2).latent_dist.mean
        err = (enc(x2) - ref).abs().max().item()
        if err > 1e-3:
            sys.exit(f"traced encoder differs from diffusers at another size (max abs {err}); try torch.jit.script")
    for name, mod in (("encoder", enc), ("decoder", dec)):
        tmp = os.path.join(a.out, f".{name}.pt.tmp")
        mod.save(tmp)
        os.replace(tmp, os.path.join(a.out, f"{name}.pt"))
    config = {"name": f"{a.model} ({a.subfolder})", "channels": channels, "downsample": downsample, "scale": scale, "shift": shift,
              "image_range": [-1, 1], "latent": "raw"}
    with open(os.path.join(a.out, "vae.json"), "w") as f:
        json.dump(config, f, indent=2)
    print(f"wrote {a.out}/encoder.pt, decoder.pt, vae.json (scale {scale}, shift {shift}, {channels} channels, /{downsample})")


if __name__ == "__main__":
    main()
