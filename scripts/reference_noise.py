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
expectation of the display-mapped reference, not the display-mapped expectation). That needs x
independent of both references. On frame 0 r₁ is the training view's reference, the fit's and
the refiner's target, whose noise a refiner reproduces in part: there only r₂ is independent of x,
and MSE(x, r₂) − σ² is the unbiased estimate. Edited frames' references have had their own seeds
since session 29 (docs/metrics.md); in folders made before, r₁ shared the target's seed on every
frame, so where the camera held still its noise was partly the target's there too. LPIPS has no
such identity: the script prints it against r₁, r₂ and their mean (twice the spp). The VAE round trip gets the same treatment: dec(enc(r₁)) against r₂, less σ².

    python3 scripts/reference_noise.py --scene-dir results-paper/cbox-specular --seed-dir noise_seed1

    python3 scripts/reference_noise.py --scene-dir results-paper/veach-bidir --seed-dir noise_seed1 \
        --size 512 --ablation

Each frame's own VAE round trip, dec(enc(r₁)), is scored as a column too (vae_roundtrip): the
floor of that frame, where Table 1's floor is the training view's.

--ablation scores Table 1's four columns (the e and ea fits' frames, the eac fit's rendered and
refined frames) and writes the experiment's Table 1 three times (paper_table.NOISE_MEASURES):
against r₁, as the experiment scores (its cells up to the PNGs' rounding), against r₂ (MSE less
σ²), and against both (LPIPS vs r̄, noise-corrected MSE), with the targets' misses under each.

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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment_lib as X  # noqa: E402


class Scorer:
    """Image pairs scored by one `latentpt metrics --pairs` process: add() every pair first, then
    run() (a process per pair spent ~1 s of its time loading libtorch and LPIPS)."""

    def __init__(self, binary, tmp):
        self.binary, self.tmp, self.pairs, self.index = binary, tmp, [], {}

    def add(self, a, b):
        """The pair's index in run()'s scores; a pair added again is scored once."""
        if (a, b) not in self.index:
            self.index[a, b] = len(self.pairs)
            self.pairs.append((a, b))
        return self.index[a, b]

    def run(self):
        listing = os.path.join(self.tmp, "pairs.txt")
        with open(listing, "w") as f:
            f.writelines(f"{a}\t{b}\n" for a, b in self.pairs)
        out = subprocess.run([self.binary, "metrics", "--pairs", listing], check=True, capture_output=True, text=True).stdout
        scores = [json.loads(line) for line in out.splitlines()]
        assert len(scores) == len(self.pairs), f"latentpt metrics --pairs scored {len(scores)} of {len(self.pairs)} pairs"
        return scores


def display_png(exr, png):
    """A cached reference holds display values in an EXR; caches written before 2026-11-30 lack the
    header mark `latentpt metrics` reads them by (it would take them for linear) until a fit or
    edit job reads them again, so hand it a 16-bit PNG of the same values (no colour conversion)."""
    subprocess.run(["oiiotool", exr, "-d", "uint16", "-o", png], check=True)


def mean_png(a, b, png):
    subprocess.run(["oiiotool", a, b, "--add", "--mulc", "0.5", "-d", "uint16", "-o", png], check=True)


def reference_stem(refs, sequence, size, spp, frame, seed_suffix=""):
    """A cached reference's path without .exr: the training view's for frame 0, else the edited
    frame's, traced with its own seed (`_own_seed`), or in folders made before that, with r₁'s."""
    traced = f"{size}x{size}_{spp}spp_clip"  # how it was traced, as pipeline/reference.cpp names it
    if frame == 0:
        return os.path.join(refs, f"training_{traced}{seed_suffix}")
    stem = os.path.join(refs, f"edits-{sequence}_{traced}_frame_{frame:04d}")
    own, shared = f"{stem}_own_seed{seed_suffix}", stem + seed_suffix
    return shared if os.path.exists(shared + ".exr") and not os.path.exists(own + ".exr") else own


def frame_row(m, x_png, r1, r2, rbar, r12):
    """One decoded frame x against the two references and their mean (`m` adds a pair to score and
    returns a function giving its scores); returns a function giving its row of MSE×100 values."""
    a, b, c = m(x_png, r1), m(x_png, r2), m(x_png, rbar)
    return lambda: {
        "mse_r1": a()["mse_x100"], "mse_r2": b()["mse_x100"], "mse_mean_ref": c()["mse_x100"],
        "mse_corrected": c()["mse_x100"] - 0.25 * r12()["mse_x100"],
        "lpips_r1": a()["lpips"], "lpips_r2": b()["lpips"], "lpips_mean_ref": c()["lpips"],
    }


# The decoded frame each column of a table scores: (edit folder of a sequence, file of frame f).
TWO_COLUMNS = {"rendered": (None, "frame_{f:04d}_rendered.png"), "refined": (None, "frame_{f:04d}.png")}
ABLATION_COLUMNS = {  # Table 1's, keyed as experiment_lib.TABLE1_COLUMNS
    "e": ("{seq}_e", "frame_{f:04d}.png"), "ea": ("{seq}_ea", "frame_{f:04d}.png"),
    "eac": ("{seq}_eac", "frame_{f:04d}_rendered.png"), "eac+refiner": ("{seq}_eac", "frame_{f:04d}.png")}


def mean(rows, key):
    return sum(r[key] for r in rows) / len(rows)


def columns_of(a, scene_dir, seq, frames):
    """{column: (folder, frame file pattern)} of one sequence. With --ablation a column lacking a
    frame is left out (an experiment folder need not keep every fit's frames); else a missing
    frame is an error, found before any metric is computed."""
    if not a.ablation:
        cols = {k: (os.path.join(scene_dir, a.folder.format(seq=seq)), png) for k, (_, png) in TWO_COLUMNS.items()}
    else:
        # only the run's fits: an older run's frames of another fit in the folder are not this run's
        fits = a.fits.split(",")
        cols = {k: (os.path.join(scene_dir, folder.format(seq=seq)), png) for k, (folder, png) in ABLATION_COLUMNS.items()
                if k.split("+")[0] in fits}
    for k, (folder, png) in list(cols.items()):
        missing = [os.path.join(folder, png.format(f=f)) for f in frames if not os.path.exists(os.path.join(folder, png.format(f=f)))]
        if missing and not a.ablation:
            sys.exit(f"reference_noise: {missing[0]} missing")
        if missing:
            print(f"reference_noise: {missing[0]} missing: column {k} left out of {seq}", file=sys.stderr)
            del cols[k]
    return cols


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene-dir", required=True)
    p.add_argument("--seed-dir", required=True, help="folder (in --scene-dir) of the second-seed edit runs")
    p.add_argument("--seed", type=int, default=1, help="the second references' --ref-seed")
    p.add_argument("--folder", default="{seq}_eac",
                   help="edit folder (in --scene-dir) of each sequence holding the decoded frames; {seq} = its name")
    p.add_argument("--ablation", action="store_true",
                   help="score Table 1's four columns ({seq}_e, {seq}_ea, {seq}_eac rendered and refined) instead "
                        "of --folder's rendered and refined frames, and write Table 1 against each reference")
    p.add_argument("--fits", default="e,ea,eac",
                   help="with --ablation: the fits whose columns are scored (an experiment's `fits`)")
    p.add_argument("--report", default="reference_noise", help="report name (.md and .json in the seed dir)")
    p.add_argument("--sequences", default="camera,object,light")
    p.add_argument("--frames", default="0,20,40")
    p.add_argument("--size", type=int, default=1024, help="reference width = height")
    p.add_argument("--ref-spp", type=int, default=512)
    p.add_argument("--bin", default="build/apps/latentpt")
    a = p.parse_args()
    refs = os.path.join(a.scene_dir, "refs")
    frames = [int(f) for f in a.frames.split(",")]
    out = os.path.join(a.scene_dir, a.seed_dir)
    with tempfile.TemporaryDirectory() as tmp:
        scorer = Scorer(a.bin, tmp)
        scores = []

        def m(x, y):  # scored later, all pairs in one process
            i = scorer.add(x, y)
            return lambda: scores[i]

        converted = {}

        def refs_of(seq, f):  # once per reference: frame 0, the training view, is in every sequence
            s1 = reference_stem(refs, seq, a.size, a.ref_spp, f)
            if s1 not in converted:
                s2 = reference_stem(refs, seq, a.size, a.ref_spp, f, f"_seed{a.seed}")
                r1, r2, rbar = (os.path.join(tmp, f"{seq}_{f}_{k}.png") for k in ("r1", "r2", "mean"))
                for exr, png in ((s1 + ".exr", r1), (s2 + ".exr", r2)):
                    display_png(exr, png)
                mean_png(r1, r2, rbar)
                converted[s1] = (s1, r1, r2, rbar, m(r1, r2))
            return converted[s1]

        columns_by_seq = {seq: columns_of(a, a.scene_dir, seq, frames) for seq in a.sequences.split(",")}
        for seq, f in [(seq, f) for seq in columns_by_seq for f in frames] + [("training", 0)]:
            for suffix in ("", f"_seed{a.seed}"):
                exr = reference_stem(refs, seq, a.size, a.ref_spp, f, suffix) + ".exr"
                if not os.path.exists(exr):
                    sys.exit(f"{exr}: missing (run render --edit --reference --ref-seed {a.seed} first)")
        pending, decoded = {}, {}
        for seq, columns in columns_by_seq.items():
            for f in frames:
                s1, r1, r2, rbar, r12 = refs_of(seq, f)
                row_of = {kind: frame_row(m, os.path.join(folder, png.format(f=f)), r1, r2, rbar, r12)
                          for kind, (folder, png) in columns.items()}
                # this frame's own VAE round trip, dec(enc(r₁)), scored as the columns are
                row_of["vae_roundtrip"] = frame_row(m, round_trip_png(a, s1, tmp, decoded), r1, r2, rbar, r12)
                pending[seq, f] = (r12, row_of)
        floor = round_trip_floor(a, m, refs_of, tmp, decoded)
        scores += scorer.run()
    result = {"sequences": {}, "floor": floor()}
    for (seq, f), (r12, row_of) in pending.items():
        row = {"frame": f, "sigma2_x100": 0.5 * r12()["mse_x100"]}
        row.update({kind: get() for kind, get in row_of.items()})
        result["sequences"].setdefault(seq, []).append(row)
        print(seq, f, json.dumps(row), flush=True)
    write_report(out, a, result)


def round_trip_png(a, stem, tmp, decoded):
    """dec(enc(r₁)) of a cached reference as a PNG, decoded once per reference (frame 0, the
    training view, is in every sequence)."""
    if stem not in decoded:
        decoded[stem] = os.path.join(tmp, f"roundtrip_{len(decoded)}.png")
        subprocess.run([a.bin, "decode", stem + "_latent.exr", "-o", decoded[stem], "-q"], check=True)
    return decoded[stem]


def round_trip_floor(a, m, refs_of, tmp, decoded):
    """The VAE round trip of the training view: dec(enc(r₁)) against r₂ less σ² is its distance
    from the converged view; against r₁ it is what the table calls the floor. LPIPS has no
    correction: dec(enc(r̄)) against r̄ is the round trip at twice the spp, the floor of the
    LPIPS-against-r̄ columns. Returns a function giving it once the pairs are scored."""
    s1, r1, r2, rbar, r12 = refs_of("training", 0)
    rt = round_trip_png(a, s1, tmp, decoded)
    rt_mean, latent_mean = (os.path.join(tmp, n) for n in ("roundtrip_mean.png", "mean.exr"))
    subprocess.run([a.bin, "encode", rbar, "-o", latent_mean, "-q"], check=True)
    subprocess.run([a.bin, "decode", latent_mean, "-o", rt_mean, "-q"], check=True)
    f1, f2, fm = m(rt, r1), m(rt, r2), m(rt_mean, rbar)
    return lambda: {"mse_r1": f1()["mse_x100"], "mse_r2_corrected": f2()["mse_x100"] - 0.5 * r12()["mse_x100"],
                    "lpips_r1": f1()["lpips"], "lpips_r2": f2()["lpips"], "lpips_mean_ref_roundtrip": fm()["lpips"],
                    "sigma2_x100": 0.5 * r12()["mse_x100"]}


def table1_lines(a, result, measure):
    """Table 1 (paper_table.py) of these frames against the reference X.NOISE_MEASURES[measure]
    names; against r₁ it reproduces the experiment's cells up to the PNGs' rounding."""
    scene = os.path.basename(os.path.normpath(a.scene_dir))
    if scene not in X.PAPER_TABLE1 or set(result["sequences"]) != set(X.KINDS):
        return [], []
    return X.table1({"scene_res": {scene: a.size}, "image_res": a.size}, {scene: X.noise_table1_entry(result, measure)})


mse_r2_less_sigma2 = X.NOISE_MEASURES["r2"][1]  # a row's column against r₂, less σ²


def write_report(out, a, result):
    lines = [f"# Reference noise on {a.scene_dir} ({a.ref_spp}-spp references, seeds 0x5eed and {a.seed})",
             "",
             "Mean over frames " + a.frames + ". MSE×100 against the experiment's reference r₁ (the table's), against "
             "the independent reference r₂ less its variance σ² (unbiased), against the mean r̄ noise-corrected; LPIPS "
             "against each. vae_roundtrip: each frame's own dec(enc(r₁)), scored the same way.", "",
             "| sequence | column | MSE×100 vs r₁ | vs r₂ − σ² | vs r̄, corrected | σ²×100 | LPIPS vs r₁ | vs r₂ | vs r̄ |",
             "|---|---|---|---|---|---|---|---|---|"]
    for seq, rows in result["sequences"].items():
        s2 = mean(rows, "sigma2_x100")
        for kind in (k for k in rows[0] if k not in ("frame", "sigma2_x100")):
            k = [r[kind] for r in rows]
            r2 = sum(mse_r2_less_sigma2(r, r[kind]) for r in rows) / len(rows)
            lines.append(f"| {seq} | {kind} | {mean(k, 'mse_r1'):.4f} | {r2:.4f} | {mean(k, 'mse_corrected'):.4f} | {s2:.4f} | "
                         f"{mean(k, 'lpips_r1'):.4f} | {mean(k, 'lpips_r2'):.4f} | {mean(k, 'lpips_mean_ref'):.4f} |")
    fl = result["floor"]
    lines += ["", f"VAE round trip of the training view: MSE×100 {fl['mse_r1']:.4f} against r₁, "
              f"{fl['mse_r2_corrected']:.4f} noise-corrected; LPIPS {fl['lpips_r1']:.4f} against r₁, "
              f"{fl['lpips_r2']:.4f} against r₂, {fl['lpips_mean_ref_roundtrip']:.4f} for r̄'s own round trip; "
              f"σ²×100 {fl['sigma2_x100']:.4f}.", ""]
    if a.ablation:
        for measure, title in (("r1", "against r₁ (the experiment's protocol)"),
                               ("r2", "against the independent reference r₂ (LPIPS vs r₂, MSE×100 vs r₂ less σ²)"),
                               ("mean", "against both references (LPIPS vs r̄, MSE×100 noise-corrected)")):
            md, misses = table1_lines(a, result, measure)
            if md:
                lines += [f"## Table 1 {title}: {len(misses)} target misses", ""] + md + [""]
                lines += [f"- {x}" for x in misses] + [""]
    for name, text in ((a.report + ".json", json.dumps(result, indent=1)), (a.report + ".md", "\n".join(lines))):
        tmp = os.path.join(out, name + ".tmp")
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, os.path.join(out, name))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
