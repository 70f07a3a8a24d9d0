#!/usr/bin/env python3
"""How much the seed moves an ablation column (issue 16 item 4, docs/results.md "What Ĩc sees").

Refits stage 1 of an experiment scene with other seeds, with the experiment's own `latentpt fit`
arguments (experiment_lib.fit_argv: same target, iterations, learning rate, no early stopping)
and no refiner, then renders each fit's edit sequences on the frames the experiment evaluated,
against its cached references (never traced again), and prints the mean rendered LPIPS /
MSE×100 per fit, seed and edit, with the change from the first fit to the second.

    python3 scripts/seed_spread.py --scene-dir results-paper/cbox-specular --fits ea,eac --seeds 1,2

Seed 0 is the experiment's own fit (<scene-dir>/fit_<name>, rendered again here without its
refiner). Results go to <scene-dir>/seed_spread/ (seed_spread.md, .json); finished fits and
frames are kept, so a stopped run continues.
"""
import argparse
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment_lib as X  # noqa: E402


def stage1_fit(c, scene, name, seed, out, log):
    """The experiment's fit `name` with `seed`, stage 1 only; seed 0 reuses the experiment's."""
    if seed == 0:
        return os.path.join(scene, "fit_" + name)
    if not os.path.exists(os.path.join(out, "fit.json")):
        argv = X.fit_argv(c, scene, name, os.cpu_count(), out, refiner=False) + ["--seed", str(seed)]
        resume = ["--resume", "--restart-if-changed"] if os.path.isdir(os.path.join(out, "checkpoint")) else []
        X.run_logged(argv + resume, log, "seed_spread")
    return out


def without_refiner(fitdir, out):
    """A copy of a fit folder without refiner.pt, so that edits score the rendered latent alone."""
    if not os.path.isdir(out):
        shutil.copytree(fitdir, out + ".tmp", ignore=shutil.ignore_patterns("checkpoint", "refiner*"))
        os.replace(out + ".tmp", out)
    return out


def scores(c, scene, fitdir, kind, frames, log):
    rows = X.edit_metrics(c["bin"], os.cpu_count(), fitdir, os.path.join(scene, f"edits-{kind}.json"),
                          os.path.join(fitdir, "edit_" + kind), c["spp"], X.ref_spp_of(c, scene),
                          os.path.join(scene, "refs"), frames, log, "seed_spread")
    return X.mean(rows, "rgb_lpips"), X.mean(rows, "rgb_mse_x100")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene-dir", required=True, help="a scene folder of an experiment run")
    ap.add_argument("--fits", default="ea,eac", help="two (or more) ablation fits, compared in this order")
    ap.add_argument("--seeds", default="1,2", help="seeds beside the experiment's 0")
    ap.add_argument("--kinds", default="camera,object,light")
    a = ap.parse_args()
    scene = os.path.abspath(a.scene_dir)
    with open(os.path.join(os.path.dirname(scene), "experiment-config.json")) as f:
        c = json.load(f)
    name = os.path.basename(scene)
    frames = X.frames_arg(c, name, a.kinds.split(",")[0])
    top = os.path.join(scene, "seed_spread")
    os.makedirs(top, exist_ok=True)
    log = os.path.join(top, "seed_spread.log")
    fits, seeds, kinds = a.fits.split(","), [0] + [int(s) for s in a.seeds.split(",")], a.kinds.split(",")
    cwd = os.getcwd()
    os.chdir(os.path.dirname(scene))  # fit.json and the experiment's paths are relative to the run folder
    res = {}
    for seed in seeds:
        for fit in fits:
            d = stage1_fit(c, name, fit, seed, os.path.join(name, "seed_spread", f"fit_{fit}_s{seed}"), log)
            d = without_refiner(d, os.path.join(name, "seed_spread", f"rendered_{fit}_s{seed}"))
            for kind in kinds:
                res.setdefault(kind, {}).setdefault(seed, {})[fit] = scores(c, name, d, kind, frames, log)
    os.chdir(cwd)
    md = [f"# Seed spread on {a.scene_dir}: frames {frames}, mean rendered LPIPS / MSE×100", "",
          "| edit | seed | " + " | ".join(fits) + " | LPIPS change | MSE×100 change |", "|---|---|" + "---|" * (len(fits) + 2)]
    for kind in kinds:
        for seed in seeds:
            r = res[kind][seed]
            (l0, m0), (l1, m1) = r[fits[0]], r[fits[-1]]
            md.append(f"| {kind} | {seed} | " + " | ".join(f"{r[f][0]:.3f} / {r[f][1]:.3f}" for f in fits) +
                      f" | {100 * (l1 / l0 - 1):+.1f} % | {100 * (m1 / m0 - 1):+.1f} % |")
    X.write_atomic(os.path.join(top, "seed_spread.md"), "\n".join(md) + "\n")
    X.write_atomic(os.path.join(top, "seed_spread.json"), json.dumps({k: {str(s): v for s, v in r.items()}
                                                                     for k, r in res.items()}, indent=1))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
