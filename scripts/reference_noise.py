#!/usr/bin/env python3
"""How much of an experiment's edit-sequence MSE is its references' own noise (issue 16).

Every metric of scripts/experiment.py compares a decoded latent x with a path-traced reference r
of finite spp. With a second reference of the same frame and another seed (`render --edit
--reference --ref-seed S`), the parallelogram law gives, exactly,

    MSE(x, r̄) = ½ (MSE(x, r₁) + MSE(x, r₂)) − ¼ MSE(r₁, r₂),    r̄ = ½ (r₁ + r₂),

and since x and the two references' noise are independent, E MSE(x, rᵢ) = MSE(x, r*) + σ² and
E MSE(r₁, r₂) = 2σ² (σ²: a reference's variance per value; r*: its expectation). So

    MSE(x, r*) ≈ MSE(x, r̄) − ¼ MSE(r₁, r₂)                       (noise-corrected)

without bias from the references' noise, up to the display mapping's curvature (r* is the
expectation of the display-mapped reference, not the display-mapped expectation). LPIPS has no
such identity: the script prints it against r₁, r₂ and their mean (twice the spp) for the trend.
The VAE round trip gets the same treatment: dec(enc(r₁)) against r₂, less σ².

    python3 scripts/reference_noise.py --scene-dir results-paper/cbox-specular --seed-dir noise_seed1

<scene-dir>/<seed-dir>/<sequence>/ are `render <scene-dir>/fit_eac --edit edits-<sequence>.json
--reference --ref-seed S --reference-cache <scene-dir>/refs` outputs for the same frames as the
experiment; their references sit in refs/ beside the experiment's, named with `_seed<S>`.
Writes <scene-dir>/<seed-dir>/reference_noise.md and .json; docs/metrics.md "Reference noise".
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile


def run_json(cmd):
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)


def display_png(exr, png):
    """A cached reference holds display values in an EXR; `latentpt metrics` reads EXRs as linear,
    so hand it a 16-bit PNG of the same values (no colour conversion)."""
    subprocess.run(["oiiotool", exr, "-d", "uint16", "-o", png], check=True)


def mean_png(a, b, png):
    subprocess.run(["oiiotool", a, b, "--add", "--mulc", "0.5", "-d", "uint16", "-o", png], check=True)


def reference_stem(refs, sequence, size, spp, frame, seed_suffix=""):
    if frame == 0:
        return os.path.join(refs, f"training_{size}x{size}_{spp}spp_clip{seed_suffix}")
    return os.path.join(refs, f"edits-{sequence}_{size}x{size}_{spp}spp_clip_frame_{frame:04d}{seed_suffix}")


def frame_row(m, x_png, r1, r2, rbar, r12):
    """One decoded frame x against the two references and their mean; MSE×100 values."""
    a, b, c = m(x_png, r1), m(x_png, r2), m(x_png, rbar)
    return {
        "mse_r1": a["mse_x100"], "mse_r2": b["mse_x100"], "mse_mean_ref": c["mse_x100"],
        "mse_corrected": c["mse_x100"] - 0.25 * r12,
        "lpips_r1": a["lpips"], "lpips_r2": b["lpips"], "lpips_mean_ref": c["lpips"],
    }


def mean(rows, key):
    return sum(r[key] for r in rows) / len(rows)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene-dir", required=True)
    p.add_argument("--seed-dir", required=True, help="folder (in --scene-dir) of the second-seed edit runs")
    p.add_argument("--seed", type=int, default=1, help="the second references' --ref-seed")
    p.add_argument("--folder", default="{seq}_eac",
                   help="edit folder (in --scene-dir) of each sequence holding the decoded frames; {seq} = its name")
    p.add_argument("--report", default="reference_noise", help="report name (.md and .json in the seed dir)")
    p.add_argument("--sequences", default="camera,object,light")
    p.add_argument("--frames", default="0,15,30,45")
    p.add_argument("--size", type=int, default=1024, help="reference width = height")
    p.add_argument("--ref-spp", type=int, default=512)
    p.add_argument("--bin", default="build/apps/latentpt")
    a = p.parse_args()
    refs = os.path.join(a.scene_dir, "refs")
    frames = [int(f) for f in a.frames.split(",")]
    out = os.path.join(a.scene_dir, a.seed_dir)
    result = {"sequences": {}, "floor": {}}
    with tempfile.TemporaryDirectory() as tmp:
        def m(x, y):
            return run_json([a.bin, "metrics", x, y, "--json"])

        def refs_of(seq, f):
            s1 = reference_stem(refs, seq, a.size, a.ref_spp, f)
            s2 = reference_stem(refs, seq, a.size, a.ref_spp, f, f"_seed{a.seed}")
            r1, r2, rbar = (os.path.join(tmp, f"{seq}_{f}_{k}.png") for k in ("r1", "r2", "mean"))
            for exr, png in ((s1 + ".exr", r1), (s2 + ".exr", r2)):
                if not os.path.exists(exr):
                    sys.exit(f"{exr}: missing (run render --edit --reference --ref-seed {a.seed} first)")
                display_png(exr, png)
            mean_png(r1, r2, rbar)
            return s1, r1, r2, rbar, m(r1, r2)["mse_x100"]

        for seq in a.sequences.split(","):
            rows = []
            for f in frames:
                s1, r1, r2, rbar, r12 = refs_of(seq, f)
                folder = os.path.join(a.scene_dir, a.folder.format(seq=seq))
                row = {"frame": f, "sigma2_x100": 0.5 * r12}
                for kind, png in (("refined", f"frame_{f:04d}.png"), ("rendered", f"frame_{f:04d}_rendered.png")):
                    row[kind] = frame_row(m, os.path.join(folder, png), r1, r2, rbar, r12)
                rows.append(row)
                print(seq, f, json.dumps(row), flush=True)
            result["sequences"][seq] = rows
        # The VAE round trip of the training view: dec(enc(r₁)) against r₂ less σ² is its
        # distance from the converged view; against r₁ it is what the table calls the floor.
        s1, r1, r2, rbar, r12 = refs_of("training", 0)
        rt = os.path.join(tmp, "roundtrip.png")
        subprocess.run([a.bin, "decode", s1 + "_latent.exr", "-o", rt, "-q"], check=True)
        f1, f2 = m(rt, r1), m(rt, r2)
        result["floor"] = {"mse_r1": f1["mse_x100"], "mse_r2_corrected": f2["mse_x100"] - 0.5 * r12,
                           "lpips_r1": f1["lpips"], "lpips_r2": f2["lpips"], "sigma2_x100": 0.5 * r12}
    write_report(out, a, result)


def write_report(out, a, result):
    lines = [f"# Reference noise on {a.scene_dir}/{a.folder} ({a.ref_spp}-spp references, seeds 0x5eed and {a.seed})",
             "",
             "Mean over frames " + a.frames + ". MSE×100: against the experiment's reference r₁ (the table's), "
             "noise-corrected (an estimate against the converged view), and the references' own variance σ²×100. "
             "LPIPS against r₁ and against the mean of both references (twice the spp).", "",
             "| sequence | column | MSE×100 vs r₁ | MSE×100 corrected | σ²×100 | LPIPS vs r₁ | LPIPS vs mean |",
             "|---|---|---|---|---|---|---|"]
    for seq, rows in result["sequences"].items():
        s2 = mean(rows, "sigma2_x100")
        for kind in ("rendered", "refined"):
            k = [r[kind] for r in rows]
            lines.append(f"| {seq} | {kind} | {mean(k, 'mse_r1'):.4f} | {mean(k, 'mse_corrected'):.4f} | {s2:.4f} | "
                         f"{mean(k, 'lpips_r1'):.4f} | {mean(k, 'lpips_mean_ref'):.4f} |")
    fl = result["floor"]
    lines += ["", f"VAE round trip of the training view: MSE×100 {fl['mse_r1']:.4f} against r₁, "
              f"{fl['mse_r2_corrected']:.4f} noise-corrected; LPIPS {fl['lpips_r1']:.4f} against r₁, "
              f"{fl['lpips_r2']:.4f} against r₂; σ²×100 {fl['sigma2_x100']:.4f}.", ""]
    for name, text in ((a.report + ".json", json.dumps(result, indent=1)), (a.report + ".md", "\n".join(lines))):
        tmp = os.path.join(out, name + ".tmp")
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, os.path.join(out, name))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
