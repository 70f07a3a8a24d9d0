#!/usr/bin/env python3
"""How a latent follows a change of light (issue 16, docs/results.md "The latent of black as the
renderer's zero").

    python3 scripts/light_response.py black ../shared/scenes/cbox/cbox_specular.xml
    python3 scripts/light_response.py slope results-paper/cbox-specular/light_eac [--rendered]
    python3 scripts/light_response.py exposure results-paper/cbox-specular/fit_eac

`black`: renders the scene in RGB, encodes its display values d and k^γ·d (a light k times brighter,
below the clip) for a few k with the VAE, and regresses two predictions of the latent's change
E(k^γ·d) − E(d) on the true one: the latent scaled about 0 (what the latent renderer's T(k·Ĩ) =
k^γ·T(Ĩ) does) and scaled about the latent of black E(0). Prints both slopes (1: the prediction
moves as the encoder does) and the RMS of E(0) and E(d).

`slope`: for an edit folder of `render --edit` (frames 0, 20, 40 with their references), the
change of the decoded frame from frame 0 to frame k, averaged over 64-pixel blocks of the linear
RGB channels, regressed on the references' change. --rendered reads the rendered latent's picture
(frame_XXXX_rendered.png) where the folder has a refiner; by default frame_XXXX.png.

`exposure`: renders a fit folder's model with every L̃e scaled by k (all its lights k times
brighter; the same seed) and regresses the decoded change, over 64-pixel blocks of linear RGB, on
the true one, clip(k·I) − clip(I) of the scene's RGB render I: 1 where the fitted model answers a
light's intensity as the scene does. The model's `background` slice (the void's look) is not
scaled. Fits with --ref-tone clip only.

Display values are linear RGB clipped to [0, 1] to the power 1/2.2, as the fit's references and
the pictures of `render --edit` (pipeline/reference.cpp display_value). Needs NumPy, the Python
module (build/python) for `black` and `exposure`, oiiotool for `slope`.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
except ImportError:
    sys.exit("light_response.py needs NumPy (python3-numpy; scripts/install-deps.sh installs it)")

GAMMA = 1 / 2.2  # the display mapping's exponent, and the tone curve's (docs/fitting.md (2))


def display(linear):
    return (np.clip(linear, 0, 1) ** GAMMA).astype(np.float32)


def display_inverse(display_values):
    return np.clip(display_values, 0, 1).astype(np.float64) ** (1 / GAMMA)


def regression_slope(predicted, true, what):
    """Least-squares slope of `predicted` on `true` through the origin."""
    p, t = predicted.ravel(), true.ravel()
    if not t @ t > 0:
        sys.exit(f"{what}: the true change is zero, so no slope can be measured")
    return float(p @ t / (t @ t))


def import_latentpt():
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "python"))
    try:
        import latentpt
    except ImportError as e:
        sys.exit(f"light_response.py needs the latentpt module (bash scripts/build.sh): {e}")
    return latentpt


def black(args):
    latentpt = import_latentpt()
    try:
        rgb = latentpt.Scene(args.scene).render(spp=args.spp, width=args.res, height=args.res, seed=1)
        vae = latentpt.Vae(args.vae_dir)
    except (ValueError, RuntimeError) as e:
        sys.exit(str(e))
    z = vae.encode(display(rgb))
    z_black = vae.encode(np.zeros_like(rgb))
    rms = lambda a: float(np.sqrt((a ** 2).mean()))  # noqa: E731
    print(f"RMS of the latent of black {rms(z_black):.3f}, of the scene's latent {rms(z):.3f}")
    for k in args.k:
        # display values scaled by k^γ: a k times brighter light below the clip, and exactly what
        # the tone curve's scaling assumes, so the regression sees the encoder alone
        change = vae.encode(k ** GAMMA * display(rgb)) - z
        scale = k ** GAMMA - 1
        about_zero = regression_slope(scale * z, change, f"k = {k:g}")
        about_black = regression_slope(scale * (z - z_black), change, f"k = {k:g}")
        print(f"k = {k:g}: slope scaled about 0 {about_zero:+.3f}, about the latent of black {about_black:+.3f}")


def exposure(args):
    latentpt = import_latentpt()
    try:
        model = latentpt.LatentScene.from_fit(args.fit)
        vae = latentpt.Vae.from_fit(args.fit)
        with open(os.path.join(args.fit, "fit.json")) as f:
            manifest = json.load(f)
    except (ValueError, RuntimeError, OSError) as e:
        sys.exit(f"{args.fit}: not a fit folder this can read: {e}")
    if manifest.get("ref_tone", "clip") != "clip":
        sys.exit(f"{args.fit}: fitted with --ref-tone {manifest['ref_tone']}; exposure compares clipped linear RGB")
    emission = [s["name"] for s in model.slices() if s["kind"] == "Le"]
    if not emission:
        sys.exit(f"{args.fit}: the model has no L̃e slice to scale")
    values, raw = {name: np.array(model.value(name), np.float32) for name in emission}, model.raw

    def decoded():
        return display_inverse(vae.decode(model.render(spp=args.spp, seed=5)))  # at the fit's latent size

    picture = decoded()
    base = block_means(picture, args.fit)
    # the fit's own scene (its defines and sampler), at the size the VAE decodes to
    rgb = model.scene.render(spp=args.spp, width=picture.shape[1], height=picture.shape[0], seed=1)
    truth_at_1 = block_means(np.clip(rgb, 0, 1), args.fit)
    measured = 0
    for k in args.k:
        try:
            for name in emission:
                model.set_value(name, k * values[name])
            scaled = block_means(decoded(), args.fit)
        except ValueError as e:
            print(f"k = {k:g}: not rendered ({e})", file=sys.stderr)
            continue
        finally:
            model.raw = raw
        truth = block_means(np.clip(k * rgb, 0, 1), args.fit) - truth_at_1
        s = regression_slope(scaled - base, truth, f"k = {k:g}")
        print(f"{args.fit} k = {k:g}: slope {s:.3f}")
        measured += 1
    if measured == 0:
        sys.exit(f"{args.fit}: no k could be rendered")


def read_linear_rgb(path, scratch):
    """A PNG's display values as linear RGB (oiiotool writes a binary PPM that NumPy reads)."""
    try:
        r = subprocess.run(["oiiotool", path, "-d", "uint8", "-o", scratch], capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit("light_response.py slope needs oiiotool (openimageio-tools)")
    if r.returncode != 0:
        sys.exit(f"{path}: oiiotool could not read it: {r.stderr.strip()}")
    with open(scratch, "rb") as f:
        parts = f.read().split(b"\n", 3)
    magic, size, maxval, data = parts if len(parts) == 4 else (b"", b"", b"", b"")
    if magic != b"P6" or maxval != b"255":
        sys.exit(f"{path}: oiiotool did not write an 8-bit binary PPM")
    w, h = map(int, size.split())
    return display_inverse(np.frombuffer(data, np.uint8).reshape(h, w, 3) / 255)


def block_means(a, path, side=64):
    h, w = a.shape[0] // side * side, a.shape[1] // side * side
    if h == 0 or w == 0:
        sys.exit(f"{path}: {a.shape[1]}x{a.shape[0]} pixels, smaller than one {side}-pixel block")
    return a[:h, :w].reshape(h // side, side, w // side, side, 3).mean(axis=(1, 3))


def slope(args):
    suffix = "_rendered" if args.rendered else ""
    with tempfile.TemporaryDirectory() as tmp:
        scratch = os.path.join(tmp, "frame.ppm")

        def frame(i, kind):
            path = os.path.join(args.folder, f"frame_{i:04d}{kind}.png")
            if not os.path.exists(path):
                sys.exit(f"{path}: missing (an edit folder with frames 0, 20, 40 and their references?)")
            return block_means(read_linear_rgb(path, scratch), path)

        ref0, out0 = frame(0, "_reference"), frame(0, suffix)
        if ref0.shape != out0.shape:
            sys.exit(f"{args.folder}: frame 0 and its reference differ in size")
        for i in args.frames:
            ref, out = frame(i, "_reference"), frame(i, suffix)
            if ref.shape != ref0.shape or out.shape != out0.shape:
                sys.exit(f"{args.folder}: frame {i} differs in size from frame 0")
            s = regression_slope(out - out0, ref - ref0, f"{args.folder} frame {i}")
            print(f"{args.folder} frame {i}: slope {s:.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    b = sub.add_parser("black", help="the latent's change under a brighter light, against two predictions")
    b.add_argument("scene")
    b.add_argument("--res", type=int, default=256, help="image side (default 256)")
    b.add_argument("--spp", type=int, default=256)
    b.add_argument("--k", type=float, nargs="+", default=[0.5, 0.8, 1.25, 2.0], help="light scales")
    b.add_argument("--vae-dir", default="", help="TAESD3 weights (default: the module's, ../shared/models/taesd3)")
    s = sub.add_parser("slope", help="how far an edit folder's frames follow the references")
    s.add_argument("folder")
    s.add_argument("--rendered", action="store_true", help="the rendered latent's picture, not the refined one")
    s.add_argument("--frames", type=int, nargs="+", default=[20, 40])
    e = sub.add_parser("exposure", help="how a fit's render answers all its lights made k times brighter")
    e.add_argument("fit")
    e.add_argument("--spp", type=int, default=64)
    e.add_argument("--k", type=float, nargs="+", default=[0.8, 1.25], help="light scales")
    args = ap.parse_args()
    bad_k = any(not math.isfinite(k) or k <= 0 or k == 1 for k in getattr(args, "k", []))
    if args.what == "exposure":
        if args.spp <= 0 or bad_k:
            ap.error("--spp must be positive, every --k positive and not 1")
        exposure(args)
    elif args.what == "black":
        if args.res <= 0 or args.res % 8 or args.spp <= 0 or bad_k:
            ap.error("--res must be a positive multiple of 8, --spp positive, every --k positive and not 1")
        black(args)
    else:
        slope(args)


if __name__ == "__main__":
    main()
