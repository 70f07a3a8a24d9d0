#!/usr/bin/env python3
"""Writes the seed inputs of tests/fuzz/corpus/<harness>/seed-* (small, valid, one feature each).

Run again only to change the seeds: `tests/fuzz/make_seeds.py --bin build/apps/latentpt`.
Files found by fuzzing sit beside them as finding-* and are never rewritten here. Seeds from
../shared (the paper's scenes, meshes, textures) are added at fuzzing time by scripts/fuzz.sh,
not committed."""
import argparse, json, os, pathlib, shutil, struct, subprocess, tempfile, zlib

HERE = pathlib.Path(__file__).resolve().parent
SRC = HERE.parent.parent
SEP = b"\n=====\n"


def put(harness, name, data):
    d = HERE / "corpus" / harness
    d.mkdir(parents=True, exist_ok=True)
    (d / ("seed-" + name)).write_bytes(data if isinstance(data, bytes) else data.encode())


OBJ = """# a quad with uvs and normals, and a triangle without
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1
f 1/1/1 2/2/1 3/3/1 4/4/1\nf 1 2 3\n"""
PLY_ASCII = """ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z
property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header
0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n"""


def ply_binary():
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
            "element face 1\nproperty list uchar uint vertex_indices\nend_header\n").encode()
    verts = b"".join(struct.pack("<6f", *p, 0, 0, 1) for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    return head + verts + struct.pack("<B3I", 3, 0, 1, 2)


def gltf_pair():
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    buf = pos + idx
    doc = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(buf)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                           {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    import base64
    text = dict(doc)
    text["buffers"] = [{"byteLength": len(buf),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}]
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    glb = (struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(buf)) +
           struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(buf), 0x004E4942) + buf)
    return json.dumps(text), glb


def png(width, height, channels, depth=8):
    colour = {1: 0, 3: 2, 4: 6}[channels]
    row = bytes(range(width * channels * depth // 8))
    raw = b"".join(b"\0" + row for _ in range(height))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def safetensors():
    f32 = struct.pack("<4f", 1, -2, 3.5, 0)
    f16 = struct.pack("<2H", 0x3C00, 0xC000)
    bf16 = struct.pack("<2H", 0x3F80, 0x4000)
    header = {"__metadata__": {"format": "pt"},
              "a": {"dtype": "F32", "shape": [2, 2], "data_offsets": [0, 16]},
              "b": {"dtype": "F16", "shape": [2], "data_offsets": [16, 20]},
              "c": {"dtype": "BF16", "shape": [1, 2], "data_offsets": [20, 24]}}
    h = json.dumps(header).encode()
    return struct.pack("<Q", len(h)) + h + f32 + f16 + bf16


def xml_scene():
    return """<scene version="3.0.0">
    <default name="spp" value="16"/>
    <default name="resx" value="32"/>
    <default name="resy" value="24"/>
    <integrator type="path"><integer name="max_depth" value="$max_depth"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$resx"/><integer name="height" value="$resy"/>
            <rfilter type="tent"/></film>
    </sensor>
    <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></bsdf>
    <bsdf type="roughconductor" id="metal"><string name="distribution" value="beckmann"/>
        <float name="alpha" value="0.2"/><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.2"/></bsdf>
    <bsdf type="dielectric" id="glass"><float name="int_ior" value="1.5"/></bsdf>
    <bsdf type="roughplastic" id="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/><float name="alpha" value="0.1"/></bsdf>
    <bsdf type="diffuse" id="textured"><texture type="bitmap" name="reflectance"><string name="filename" value="@DIR@/asset.png"/></texture></bsdf>
    <shape type="rectangle"><ref id="white"/><transform name="to_world"><scale x="4" y="4"/><rotate x="1" angle="-90"/></transform></shape>
    <shape type="cube"><ref id="metal"/><transform name="to_world"><scale value="0.3"/><translate x="-1" y="0.3"/></transform></shape>
    <shape type="sphere"><point name="center" x="1" y="0.4" z="0"/><float name="radius" value="0.4"/><ref id="glass"/></shape>
    <shape type="obj"><string name="filename" value="@DIR@/asset.obj"/><boolean name="face_normals" value="true"/><ref id="textured"/></shape>
    <shape type="ply"><string name="filename" value="@DIR@/asset.ply"/><ref id="plastic"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.3"/><rotate x="1" angle="90"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="10, 10, 10"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.1, 0.1"/></emitter>
</scene>
"""


def json_scene():
    s = json.loads((SRC / "scenes/cornell-box/scene.json").read_text())
    s["resolution"] = [16, 12]
    return json.dumps(s, indent=1)


def fit_state(binary, param="code"):
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "fit"
        subprocess.run([binary, "fit", str(SRC / "scenes/cornell-box/scene.json"), "--out", str(out),
                        "--synthetic-res", "4x4", "--iterations", "3", "--spp", "1", "--final-spp", "1",
                        "--no-refiner", "--checkpoint-every", "2", "--reuse-paths", "0", "--param", param, "-q"],
                       check=True)
        fit = json.loads((out / "fit.json").read_text())
        fit["scene"] = "@DIR@/scene.json"
        state = json.loads((out / "checkpoint/state.json").read_text())
        tag = state["tag"]
        state["tag"] = "t"
        ck = out / "checkpoint"
        return SEP.join([json.dumps(fit, indent=1).encode(), (out / "params.json").read_bytes(),
                         json.dumps(state).encode(), (ck / f"params-{tag}.json").read_bytes(),
                         (ck / f"adam-{tag}.bin").read_bytes()])


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--bin", default=str(SRC / "build/apps/latentpt"))
    a = ap.parse_args()
    put("obj", "quad.obj", OBJ)
    put("ply", "ascii.ply", PLY_ASCII)
    put("ply", "binary.ply", ply_binary())
    text, glb = gltf_pair()
    put("gltf", "triangle.gltf", text)
    put("gltf", "triangle.glb", glb)
    put("image", "rgb8.png", png(4, 3, 3))
    put("image", "rgba8.png", png(2, 2, 4))
    put("image", "grey16.png", png(3, 2, 1, 16))
    put("image", "tiny.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n" + bytes([128, 64, 32, 129] * 4))
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in [("rgb.exr", ["--pattern", "fill:top=0.1,0.2,0.3:bottom=1,2,3", "4x3", "3"]),
                           ("latent.exr", ["--pattern", "noise", "2x2", "16", "--chnames",
                                           ",".join(f"C{c}" for c in range(16)), "-d", "half"])]:
            path = os.path.join(tmp, name)
            subprocess.run(["oiiotool", *args, "-o", path], check=True)
            put("image", name, pathlib.Path(path).read_bytes())
    put("safetensors", "three_dtypes", safetensors())
    put("vae_json", "sd35.json", json.dumps({"channels": 16, "downsample": 8, "scale": 1.5305, "shift": 0.0609,
                                             "image_range": [-1, 1], "latent": "raw"}))
    put("edits", "demo.json", (SRC / "scenes/cornell-box/edits-demo.json").read_bytes())
    put("scene_json", "cornell_box.json", json_scene())
    put("scene_json", "mesh_and_texture.json", json.dumps({
        "camera": {"type": "perspective", "fov": 45, "origin": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0]},
        "resolution": [8, 8],
        "materials": {"t": {"type": "diffuse", "reflectance": {"type": "bitmap", "filename": "@DIR@/asset.png"}}},
        "shapes": [{"type": "obj", "filename": "@DIR@/asset.obj", "material": "t"},
                   {"type": "ply", "filename": "@DIR@/asset.ply", "material": "t",
                    "emitter": {"type": "area", "radiance": [1, 1, 1]}}]}, indent=1))
    put("scene_xml", "features.xml", xml_scene())
    put("fit_state", "cornell_box", fit_state(a.bin))
    put("fit_state", "cornell_box_gain", fit_state(a.bin, "gain"))  # a log-gain entry per Le slice


if __name__ == "__main__":
    main()
