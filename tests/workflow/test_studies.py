#!/usr/bin/env python3
"""scripts/refiner_study.py, seed_spread.py and reference_noise.py on a copy of experiment.quick's folder
(the ctest fixture): each study scores, by its own path, a cell that the experiment scored, and
must give the experiment's number; what the study itself adds (a retrained refiner, another
seed) must really differ from what it copied. 60 s in CI (2 cores).

    tests/workflow/test_studies.py --bin build/apps/latentpt --experiment build/experiment-quick --out build/studies

- refiner_study 'default' (the eac fit's own refiner, rendered again) = the experiment's
  eac+refiner means per edit; its retrained 'mse_ssim' variant trains the steps asked for on its
  own loss (MSE + D-SSIM), and a second run asking other iterations of that folder is an error.
- seed_spread: seed 0 (the experiment's fits, rendered again) = the experiment's e and ea means;
  seed 1 refits with seed 1 and lands elsewhere.
- experiment.py --second-references on a copy of the finished experiment: runs only the second
  references' jobs and reference_noise --ablation (a second run, nothing); against the first
  references its four Table 1 columns are the experiment's metrics.csv cells, the parallelogram
  law ties the MSE against the mean reference to the two MSEs and the references' spread, and
  the spread is not zero.
Exit 77 (skipped) without the experiment's folder."""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = "cbox-specular"
KINDS = ["camera", "light"]
ALL_KINDS = ["camera", "object", "light"]


def close(a, b, rel=1e-4):
    return math.isfinite(a) and math.isfinite(b) and abs(a - b) <= rel * max(abs(a), abs(b), 1e-12)


def script(name, *args):
    return [sys.executable, os.path.join(ROOT, "scripts", name), *args]


def copy_experiment(src, out):
    """What the studies read (the config, the edit files, the reference cache, the fits); they
    write into the copy's scene folder. Returns the experiment's per-edit cells (summary.json)."""
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(os.path.join(out, SCENE))
    shutil.copy(os.path.join(src, "experiment-config.json"), out)
    for kind in KINDS:
        shutil.copy(os.path.join(src, SCENE, f"edits-{kind}.json"), os.path.join(out, SCENE))
    for folder in ("refs", "fit_e", "fit_ea", "fit_eac"):
        shutil.copytree(os.path.join(src, SCENE, folder), os.path.join(out, SCENE, folder),
                        ignore=shutil.ignore_patterns("checkpoint", "edit_*"))
    with open(os.path.join(src, "summary.json")) as f:
        return json.load(f)["scenes"][SCENE]["edits"]


def check_refiner_study(a, scene_dir, edits):
    run = script("refiner_study.py", "--scene-dir", scene_dir, "--bin", a.bin, "--kinds", ",".join(KINDS),
                 "--variants", "default,mse_ssim", "--iterations", "20")
    subprocess.run(run, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(scene_dir, "refiner_study", "study.json")) as f:
        study = json.load(f)
    for kind in KINDS:
        ours, theirs = study["default"][kind], edits[kind]["eac+refiner"]
        assert close(ours["lpips"], theirs["rgb_lpips"]) and close(ours["mse_x100"], theirs["rgb_mse_x100"]), \
            f"refiner_study default {kind}: {ours} against the experiment's eac+refiner {theirs}"
    with open(os.path.join(scene_dir, "refiner_study", "mse_ssim", "refiner_loss.csv")) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 20, f"mse_ssim trained {len(rows)} steps, not 20"
    for r in rows:  # the variant's loss: latent MSE + D-SSIM, no LPIPS (the fit's refiner: MSE alone)
        mse, dssim, lpips, loss = (float(r[k]) for k in ("mse", "dssim", "lpips", "loss"))
        assert dssim > 0 and lpips == 0 and close(loss, mse + dssim, 1e-5), f"mse_ssim's loss row {r}"
    assert not close(study["mse_ssim"]["camera"]["mse_x100"], study["default"]["camera"]["mse_x100"]), \
        "the retrained refiner scores exactly as the fit's: it was not retrained"
    again = run[:run.index("--variants") + 1] + ["default"] + run[run.index("--variants") + 2:]
    subprocess.run(again, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(scene_dir, "refiner_study", "study.json")) as f:
        kept = json.load(f)
    assert kept.get("mse_ssim") == study["mse_ssim"] and kept["default"] == study["default"], \
        "a later run of one variant dropped or changed another variant's row of study.json"
    other = subprocess.run(run[:-1] + ["21"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert other.returncode != 0 and "other settings" in other.stderr, \
        f"a folder made with 20 iterations was reused for 21 (exit {other.returncode}: {other.stderr})"


def check_seed_spread(scene_dir, edits):
    subprocess.run(script("seed_spread.py", "--scene-dir", scene_dir, "--fits", "e,ea", "--seeds", "1",
                          "--kinds", ",".join(KINDS)), check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(scene_dir, "seed_spread", "seed_spread.json")) as f:
        spread = json.load(f)
    for kind in KINDS:
        for fit in ("e", "ea"):
            (lp, mse), theirs = spread[kind]["0"][fit], edits[kind][fit]
            assert close(lp, theirs["rgb_lpips"]) and close(mse, theirs["rgb_mse_x100"]), \
                f"seed_spread seed 0 {kind}/{fit}: {lp} / {mse} against the experiment's {theirs}"
            assert not close(spread[kind]["1"][fit][1], mse), f"seed 1's {fit} fit scores as seed 0's"
    with open(os.path.join(scene_dir, "seed_spread", "fit_ea_s1", "fit.json")) as f:
        assert json.load(f).get("seed") == 1, "seed_spread's seed-1 fit does not record seed 1"


def benchmarks(out):
    """{benchmark file: mtime} of the scene's jobs: which jobs a workflow run ran."""
    d = os.path.join(out, SCENE, "benchmarks")
    return {n: os.path.getmtime(os.path.join(d, n)) for n in os.listdir(d)}


def check_second_references(a, src, out):
    """experiment.py --second-references on a copy of the quick experiment: it runs the second
    references' jobs and the scores alone (every other job is kept), a second run runs nothing;
    against the first references its four Table 1 columns are the experiment's metrics.csv cells
    on every scored frame, the parallelogram law ties the MSE against the mean reference to the
    two MSEs and the references' spread, the spread is not zero, and summary.md holds the table."""
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(src, out, symlinks=True)
    with open(os.path.join(out, "experiment-config.json")) as f:
        config = json.load(f)
    before = benchmarks(out)
    run = script("experiment.py", "--quick", "--second-references", "--bin", config["bin"], "--shared", config["shared"],
                 "--out", out)
    subprocess.run(run, check=True, stdout=subprocess.DEVNULL)
    after = benchmarks(out)
    ran = sorted(n for n in after if before.get(n) != after[n])
    assert ran == sorted([f"noise_{kind}.tsv" for kind in ALL_KINDS] + ["noise_scores.tsv"]), \
        f"--second-references on a finished experiment ran {ran}"
    subprocess.run(run, check=True, stdout=subprocess.DEVNULL)
    assert benchmarks(out) == after, "a second run of a finished --second-references experiment ran jobs again"
    scene_dir = os.path.join(out, SCENE)
    with open(os.path.join(scene_dir, "noise_seed1", "reference_noise.json")) as f:
        result = json.load(f)
    cells = {"e": ("e", "rgb_"), "ea": ("ea", "rgb_"), "eac": ("eac", "rgb_"), "eac+refiner": ("eac", "refined_rgb_")}
    for kind in ALL_KINDS:
        rows = result["sequences"][kind]
        assert [r["frame"] for r in rows] == [0, 1, 2], f"{kind}: scored frames {[r['frame'] for r in rows]}"
        for row in rows:
            assert row["sigma2_x100"] > 0, f"{kind} frame {row['frame']}: the seed-1 reference equals the first one"
            for col, (fit, prefix) in cells.items():
                with open(os.path.join(scene_dir, f"{kind}_{fit}", "metrics.csv")) as f:
                    theirs = next(r for r in csv.DictReader(f) if int(r["frame"]) == row["frame"])
                ours = row[col]
                # PNG rounding: the experiment scores its float frames, the script their PNGs
                assert close(ours["mse_r1"], float(theirs[prefix + "mse_x100"]), 2e-3) and \
                    abs(ours["lpips_r1"] - float(theirs[prefix + "lpips"])) < 2e-3, \
                    f"{kind}/{col} frame {row['frame']} against r1: {ours} against the experiment's {theirs}"
                law = 0.5 * (ours["mse_r1"] + ours["mse_r2"]) - 0.5 * row["sigma2_x100"]
                assert close(ours["mse_mean_ref"], law, 1e-2), f"{kind}/{col}: parallelogram law {ours} against {law}"
        # frame 0's own round trip is the training view's: the floor
        assert close(rows[0]["vae_roundtrip"]["mse_r1"], result["floor"]["mse_r1"], 1e-9), (rows[0], result["floor"])
    with open(os.path.join(scene_dir, "noise_seed1", "reference_noise.md")) as f:
        md = f.read()
    for table in ("r₁", "the independent reference r₂", "both references"):
        assert f"## Table 1 against {table}" in md, md
    with open(os.path.join(out, "summary.md")) as f:
        summary = f.read()
    assert "## Table 1 against an independent reference per frame" in summary, summary
    with open(os.path.join(out, "report.html")) as f:
        report = f.read()
    assert "<h2>Table 1 layout" in report and "<h2>Table 1 against an independent reference" in report, \
        "report.html lacks the Table 1 tables"
    with open(os.path.join(out, "summary.json")) as f:
        assert json.load(f)["reference_noise"][SCENE] == result, "summary.json lacks the reference_noise result"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True)
    ap.add_argument("--experiment", required=True, help="experiment.quick's output folder")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    if not os.path.exists(os.path.join(a.experiment, "summary.json")):
        print(f"test_studies: no finished experiment at {a.experiment}", file=sys.stderr)
        return 77
    edits = copy_experiment(a.experiment, a.out)
    scene_dir = os.path.join(a.out, SCENE)
    check_refiner_study(a, scene_dir, edits)
    check_seed_spread(scene_dir, edits)
    check_second_references(a, a.experiment, a.out + "-second-references")
    print("test_studies: the three studies reproduce the experiment's cells and add what they say")
    return 0


if __name__ == "__main__":
    sys.exit(main())
