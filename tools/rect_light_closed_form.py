#!/usr/bin/env python3
"""Direct light from a rectangle emitter onto a diffuse rectangle, per pixel, in closed form.

A check that needs no other renderer: at max_depth 2 (Mitsuba's count: emitters seen directly plus
one bounce of direct light), a pixel that sees an unoccluded diffuse receiver lit by one rectangle
emitter has the value

    I = rho / pi * L * E,   E = 1/2 |sum_k beta_k  n . (u_k x u_k+1) / |u_k x u_k+1||

(Lambert's formula for a polygon's form factor: u_k the unit vectors from the shading point to the
emitter's corners, beta_k the angle between consecutive ones, n the receiver's normal), and zero
behind the one-sided emitter. The script evaluates it on a grid of sub-pixel positions (the box
filter's footprint) over a region of the image and prints the ratio render / closed form per band
of rows for each render it is given. With two renders of one renderer (independent seeds) it also
prints the noise of each ratio (half the difference of the two). It writes a picture of the
ratios (PNG through oiiotool): one strip per renderer, top to bottom, red where brighter, blue where darker.

Used on Bitterli's Cornell box (docs/validation.md, "Cornell box: blocks beside the light"), where
Cycles reads the back wall's top band darker than ours and Tungsten.

usage:
  rect_light_closed_form.py SCENE.xml --emitter ID --receiver ID --rows A:B --cols A:B
        --res N [--sub S] [--range R] [--png FILE] LABEL=EXR[,EXR] ...

  SCENE.xml      the Mitsuba 3 scene the renders were made from (rectangles and a perspective
                 sensor whose to_world is matrix / translate / scale, tools/mitsuba_transform.py;
                 the receiver's BSDF diffuse or twosided diffuse)
  --emitter ID   id of the rectangle shape carrying the area emitter
  --receiver ID  id of the diffuse rectangle to check
  --rows A:B     image rows A..B-1 to check (the receiver must be unoccluded there, both from the
                 camera and from the emitter: the script does not trace shadows)
  --cols A:B     image columns A..B-1
  --res N        the renders' square resolution
  --sub S        S x S sub-pixel positions per pixel (default 6): box-filtered renders
  --band K       rows per band in the table (default 4)
  --range R      colour scale of the picture: ratios 1 +- R (default 0.05)
  --png FILE     write the picture there
  LABEL=EXR[,EXR]  a renderer's render(s) at max_depth 2, box filter (two: independent seeds)

Exit status 0; 2 on bad input (the message names the file and field). Python standard library,
numpy and oiiotool (openimageio-tools) only.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

import mitsuba_transform


def fail(msg):
    print(f"rect_light_closed_form: {msg}", file=sys.stderr)
    sys.exit(2)


def floats_of(node, where):
    text = node.get("value")
    try:
        return [float(v) for v in (text or "").replace(",", " ").split()]
    except ValueError:
        fail(f"{where}: value '{text}' is not a list of numbers")


def matrix_of(elem, where):
    flip = elem.find("boolean[@name='flip_normals']")
    if flip is not None and flip.get("value") == "true":
        fail(f"{where}: flip_normals is not read by this check")
    try:
        m = mitsuba_transform.to_world(elem, where)
    except ValueError as e:
        fail(str(e))
    if m is None:
        fail(f"{where}: to_world uses a transform this check does not read (matrix, translate, scale only)")
    return np.array(m, dtype=float)


def rgb_of(elem, name, where):
    node = elem.find(f"rgb[@name='{name}']")
    if node is None:
        fail(f"{where}: no <rgb name=\"{name}\">")
    vals = floats_of(node, f"{where} rgb '{name}'")
    if len(vals) not in (1, 3):
        fail(f"{where}: rgb '{name}' needs 1 or 3 values, got {len(vals)}")
    return np.array(vals if len(vals) == 3 else vals * 3)


def load_scene(path, emitter_id, receiver_id):
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        fail(f"{path}: {e}")
    shapes = {s.get("id"): s for s in root.iter("shape")}
    bsdfs = {b.get("id"): b for b in root.iter("bsdf") if b.get("id")}
    for sid in (emitter_id, receiver_id):
        if sid not in shapes or shapes[sid].get("type") != "rectangle":
            fail(f"{path}: no rectangle shape with id '{sid}'")
    em = shapes[emitter_id].find("emitter[@type='area']")
    if em is None:
        fail(f"{path}: shape '{emitter_id}' has no area emitter")
    radiance = rgb_of(em, "radiance", f"{path}: shape '{emitter_id}' emitter")
    rec = shapes[receiver_id]
    bsdf = rec.find("bsdf")
    if bsdf is None:
        ref = rec.find("ref")
        bsdf = bsdfs.get(ref.get("id")) if ref is not None else None
    twosided = bsdf is not None and bsdf.get("type") == "twosided"
    while bsdf is not None and bsdf.get("type") == "twosided":
        bsdf = bsdf.find("bsdf")
    if bsdf is None or bsdf.get("type") != "diffuse":
        fail(f"{path}: shape '{receiver_id}' must have a diffuse BSDF")
    rho = rgb_of(bsdf, "reflectance", f"{path}: shape '{receiver_id}' bsdf")
    sensor = root.find("sensor")
    if sensor is None or sensor.get("type") != "perspective":
        fail(f"{path}: needs a perspective <sensor>")
    fov = sensor.find("float[@name='fov']")
    if fov is None:
        fail(f"{path}: sensor has no fov")
    axis = sensor.find("string[@name='fov_axis']")
    if axis is not None and axis.get("value") != "x":
        fail(f"{path}: sensor fov_axis '{axis.get('value')}' (only x is read)")
    return dict(light=matrix_of(shapes[emitter_id], f"{path}: shape '{emitter_id}'"),
                receiver=matrix_of(rec, f"{path}: shape '{receiver_id}'"),
                camera=matrix_of(sensor, f"{path}: sensor"),
                fov=floats_of(fov, f"{path}: sensor fov")[0], radiance=radiance, rho=rho, twosided=twosided)


def camera_rays(scene, res, rows, cols, sub):
    """World-space origin and directions for sub x sub positions in each pixel of the region."""
    j, i, b, a = np.meshgrid(np.arange(*rows), np.arange(*cols), np.arange(sub), np.arange(sub),
                             indexing="ij")
    px = (i + (a + 0.5) / sub) / res
    py = (j + (b + 0.5) / sub) / res
    t = math.tan(math.radians(scene["fov"]) / 2)
    # Mitsuba's camera looks down local +z, +y up; image +x runs towards local -x.
    local = np.stack([-(2 * px - 1) * t, -(2 * py - 1) * t, np.ones_like(px)], -1)
    cam = scene["camera"]
    return cam[:3, 3], local @ cam[:3, :3].T


def receiver_points(scene, origin, dirs):
    m = scene["receiver"]
    centre, normal = m[:3, 3], np.linalg.inv(m[:3, :3]).T @ np.array([0, 0, 1.0])
    normal /= np.linalg.norm(normal)
    t = ((centre - origin) @ normal) / (dirs @ normal)
    p = origin + t[..., None] * dirs
    uv = (p - centre) @ np.linalg.inv(m[:3, :3]).T  # receiver-local coordinates
    inside = (np.abs(uv[..., 0]) <= 1) & (np.abs(uv[..., 1]) <= 1) & (t > 0)
    return p, normal, inside


def check_sides(scene, origin):
    """The formula counts the whole emitter: it must lie on the side of the receiver the camera
    sees, and a one-sided receiver must be seen from its front."""
    m, light = scene["receiver"], scene["light"]
    centre = m[:3, 3]
    normal = np.linalg.inv(m[:3, :3]).T @ np.array([0, 0, 1.0])
    cam_side = (origin - centre) @ normal
    if not scene["twosided"] and cam_side <= 0:
        return "the camera sees the back of the one-sided receiver"
    for x, y in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
        corner = (light @ np.array([x, y, 0, 1.0]))[:3]
        if ((corner - centre) @ normal) * cam_side <= 0:
            return "the emitter is not wholly on the camera's side of the receiver"
    return None


def polygon_irradiance_factor(scene, p, n):
    """|sum beta_k n.c_k| / 2 for the emitter's quad; zero behind its emitting (+z local) side."""
    m = scene["light"]
    corners = [(m @ np.array([x, y, 0, 1.0]))[:3] for x, y in [(-1, -1), (1, -1), (1, 1), (-1, 1)]]
    n_light = np.linalg.inv(m[:3, :3]).T @ np.array([0, 0, 1.0])
    u = [(c - p) / np.linalg.norm(c - p, axis=-1, keepdims=True) for c in corners]
    s = np.zeros(p.shape[:-1])
    for k in range(4):
        c = np.cross(u[k], u[(k + 1) % 4])
        beta = np.arccos(np.clip(np.sum(u[k] * u[(k + 1) % 4], -1), -1, 1))
        s += beta * (c @ n) / np.linalg.norm(c, axis=-1)
    front = (p - m[:3, 3]) @ n_light > 0
    return np.where(front, 0.5 * np.abs(s), 0.0)


def read_exr(path, res):
    try:
        out = subprocess.run(["oiiotool", "--info", "--dumpdata", path], capture_output=True, text=True)
    except OSError as e:
        fail(f"{path}: cannot run oiiotool (openimageio-tools): {e}")
    if out.returncode != 0:
        fail(f"{path}: oiiotool could not read it: {out.stderr.strip()}")
    img = np.zeros((res, res, 3))
    n = 0
    for line in out.stdout.splitlines():
        line = line.strip()
        if line.startswith("Pixel ("):
            head, vals = line.split(":", 1)
            x, y = (int(v) for v in head[7:-1].split(","))
            if x >= res or y >= res:
                fail(f"{path}: larger than --res {res}")
            img[y, x] = [float(v) for v in vals.split()[:3]]
            n += 1
    if n != res * res:
        fail(f"{path}: {n} pixels, expected {res}x{res}")
    return img


def diverging(ratio, rng):
    """1 -> white, 1+rng -> red, 1-rng -> blue (8-bit RGB)."""
    d = np.clip((ratio - 1) / rng, -1, 1)
    rgb = np.ones(ratio.shape + (3,))
    rgb[..., 1] -= np.abs(d)
    rgb[..., 2] -= np.clip(d, 0, 1)
    rgb[..., 0] -= np.clip(-d, 0, 1)
    return (rgb * 255 + 0.5).astype(np.uint8)


def write_png(path, strips, scale):
    gap = np.full((4, strips[0].shape[1], 3), 128, np.uint8)
    row = np.concatenate(sum(([s, gap] for s in strips), [])[:-1], axis=0)
    row = row.repeat(scale, 0).repeat(scale, 1)
    folder = os.path.dirname(os.path.abspath(path))
    with tempfile.TemporaryDirectory(dir=folder) as tmpdir:  # beside the output: os.replace is atomic
        ppm, png = os.path.join(tmpdir, "ratio.ppm"), os.path.join(tmpdir, "ratio.png")
        with open(ppm, "wb") as f:
            f.write(f"P6 {row.shape[1]} {row.shape[0]} 255\n".encode())
            f.write(row.tobytes())
        try:
            done = subprocess.run(["oiiotool", ppm, "-o", png], capture_output=True, text=True)
        except OSError as e:
            fail(f"--png {path}: cannot run oiiotool (openimageio-tools): {e}")
        if done.returncode != 0:
            fail(f"--png {path}: oiiotool could not write it: {done.stderr.strip()}")
        os.replace(png, path)


def parse_range(text, name):
    try:
        a, b = (int(v) for v in text.split(":"))
    except ValueError:
        fail(f"{name} '{text}': expected A:B")
    if not 0 <= a < b:
        fail(f"{name} '{text}': expected 0 <= A < B")
    return a, b


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("renders", nargs="+", metavar="LABEL=EXR[,EXR]")
    ap.add_argument("--emitter", required=True)
    ap.add_argument("--receiver", required=True)
    ap.add_argument("--rows", required=True)
    ap.add_argument("--cols", required=True)
    ap.add_argument("--res", type=int, required=True)
    ap.add_argument("--sub", type=int, default=6)
    ap.add_argument("--band", type=int, default=4)
    ap.add_argument("--range", type=float, default=0.05)
    ap.add_argument("--png")
    args = ap.parse_args()
    rows, cols = parse_range(args.rows, "--rows"), parse_range(args.cols, "--cols")
    if rows[1] > args.res or cols[1] > args.res:
        fail("--rows/--cols reach outside the image")
    for name, value in (("--sub", args.sub), ("--band", args.band), ("--res", args.res)):
        if value < 1:
            fail(f"{name} {value}: must be at least 1")
    if not args.range > 0:
        fail(f"--range {args.range}: must be positive")
    scene = load_scene(args.scene, args.emitter, args.receiver)

    origin, dirs = camera_rays(scene, args.res, rows, cols, args.sub)
    problem = check_sides(scene, origin)
    if problem:
        fail(f"{args.scene}: '{args.receiver}' and '{args.emitter}': {problem}")
    p, n, inside = receiver_points(scene, origin, dirs)
    if not inside.all():
        fail(f"--rows {args.rows} --cols {args.cols}: part of the region does not see '{args.receiver}'")
    geom = polygon_irradiance_factor(scene, p, n).mean(axis=(2, 3))  # box filter
    closed = geom[..., None] * scene["rho"] / math.pi * scene["radiance"]
    lum = closed.sum(-1)

    strips, print_rows = [], []
    for spec in args.renders:
        if "=" not in spec:
            fail(f"'{spec}': expected LABEL=EXR[,EXR]")
        label, paths = spec.split("=", 1)
        imgs = [read_exr(q, args.res)[rows[0]:rows[1], cols[0]:cols[1]] for q in paths.split(",")]
        mean = sum(imgs) / len(imgs)
        ratio = np.divide(mean.sum(-1), lum, out=np.ones_like(lum), where=lum > 0)
        strips.append(diverging(ratio, args.range))
        print(f"{label} / closed form ({' + '.join(paths.split(','))}):")
        r = mean.reshape(-1, 3).sum(0) / closed.reshape(-1, 3).sum(0)
        print(f"  whole region rows {args.rows} cols {args.cols}: R / G / B {r[0]:.4f} {r[1]:.4f} {r[2]:.4f}")
        for y0 in range(0, rows[1] - rows[0], args.band):
            sl = slice(y0, y0 + args.band)
            val = mean[sl].sum() / closed[sl].sum()
            noise = ""
            if len(imgs) == 2:
                noise = f" +- {abs(imgs[0][sl].sum() - imgs[1][sl].sum()) / closed[sl].sum() / 2:.4f}"
            print(f"  rows {rows[0] + y0:4d}-{min(rows[0] + y0 + args.band, rows[1]) - 1:4d}: {val:.4f}{noise}")
    if args.png:
        write_png(args.png, strips, max(1, 640 // strips[0].shape[1]))
        print(f"wrote {args.png}: strips {', '.join(s.split('=')[0] for s in args.renders)}, "
              f"ratio 1 +- {args.range} (red brighter, blue darker)")


if __name__ == "__main__":
    main()
