#!/usr/bin/env python3
"""Refiner variants judged by edited views (issue 16, docs/results.md "Refiner study").

Every variant but 'default' retrains the refiner of one stage-1 fit (a copy of the fit folder,
the refiner removed) with `latentpt refine <options>`; each then renders the experiment's edit sequences with it
against the experiment's path-traced references (read from its reference cache, never traced
again; an experiment folder made before session 29 lacks the edited frames' own-seed references,
docs/metrics.md, so the first variant traces them, and rows of earlier runs kept in study.md
were scored against the old ones: start such a study in a fresh folder) and reports the mean
refined LPIPS / MSE×100 over the edited frames. Training uses the single training view only:
no edited frame or its reference ever reaches `refine`. Defaults are chosen by the edit means;
the training view's numbers are printed beside them, not used.

    python3 scripts/refiner_study.py --scene-dir results-paper/cbox-specular --variants mse_only,whole_view

<scene-dir> is a scene folder of scripts/experiment.py (fit_eac/, refs/, edits-*.json). The
frames, spp and reference spp default to the experiment's (its experiment-config.json beside the
scene folder), so the references come from its cache. Results go to
<scene-dir>/refiner_study/<variant>/ and study.md / study.json there; finished variants and
frames are kept (run again to continue). The 'default' variant is the fit's own refiner, not
retrained: the experiment's +refiner column, scored again.
"""
import argparse
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment_lib as X  # noqa: E402

# "Ours" below is our loss mix MSE + D-SSIM + LPIPS, the refiner's default until 2026-11-25; the
# default is now latent MSE alone, so variants that do not set a loss weight get the mix spelled
# out (with_mix) and still test what they say and what docs/results.md measured.
MIX = ["--w-ssim", "1", "--w-lpips", "1"]
MSE = ["--w-ssim", "0", "--w-lpips", "0", "--lpips-crop", "0"]  # the default's loss, spelled out

# name -> (what it tests, `latentpt refine` options, drop the path-traced RGB so that LPIPS
# compares with the decoded target as in the paper's loss, iterations: None = --iterations);
# None options: keep the fit's refiner
VARIANTS = {
    "default": ("the fit's refiner, as the fit trained it (latent MSE alone since 2026-11-25; before, ours)", None,
                False, None),
    "no_norm": ("no InstanceNorm (crops and whole views see one function)", ["--norm", "none"], False, None),
    "paper": ("the paper's text where it differs: no InstanceNorm, LPIPS to dec(target), lr 1e-4 (crops, dropout, "
              "iterations ours)", ["--norm", "none", "--lr", "1e-4"], True, None),
    "mse_only": ("the paper code's latent MSE alone", ["--w-ssim", "0", "--w-lpips", "0", "--lpips-crop", "0"], False,
                 None),
    "lpips_to_target": ("LPIPS against dec(target), the paper's loss, not the path-traced RGB", [], True, None),
    "whole_view": ("whole-view training (InstanceNorm statistics as at inference)", ["--crop", "0", "--lpips-crop", "32"],
                   False, None),
    "lr_1e-4": ("the paper's learning rate 1e-4", ["--lr", "1e-4"], False, None),
    "mse_x10": ("latent MSE weighted 10", ["--w-mse", "10"], False, None),
    "expansion_8": ("half the width (expansion 8)", ["--expansion", "8"], False, None),
    "no_dropout": ("dropout 0", ["--dropout", "0"], False, None),
    "mse_ssim": ("latent MSE + D-SSIM, no LPIPS (no decoder in the loop: a quarter of the step's time)",
                 ["--w-ssim", "1", "--w-lpips", "0", "--lpips-crop", "0"], False, None),
    "mse_only_long": ("latent MSE alone for 3000 iterations (about the default's training time)",
                      ["--w-ssim", "0", "--w-lpips", "0", "--lpips-crop", "0"], False, 3000),
    "mse_ssim_long": ("latent MSE + D-SSIM for 3000 iterations", ["--w-ssim", "1", "--w-lpips", "0", "--lpips-crop", "0"],
                      False, 3000),
    "mse_only_crop64": ("latent MSE alone on 64² crops (4× the pixels per step; InstanceNorm nearer the whole view)",
                        ["--crop", "64", "--w-ssim", "0", "--w-lpips", "0", "--lpips-crop", "0"], False, None),
    "noise_views_8": ("latent MSE alone on 8 renders of the training view with independent noise (the fit's + 7)",
                      MSE + ["--noise-views", "8"], False, None),
    "noise_views_4": ("latent MSE alone on 4 renders of the training view with independent noise", MSE +
                      ["--noise-views", "4"], False, None),
    "paper_code": ("the paper code's refiner: latent MSE alone, lr 1e-4, no InstanceNorm", MSE +
                   ["--lr", "1e-4", "--norm", "none"], False, None),
    "mse_no_norm": ("latent MSE alone without InstanceNorm", MSE + ["--norm", "none"], False, None),
    "mse_no_dropout": ("latent MSE alone, dropout 0", MSE + ["--dropout", "0"], False, None),
    "mse_cosine": ("latent MSE alone, lr falling along a half cosine to 0", MSE + ["--lr-decay", "cosine"], False, None),
    "mse_9000": ("latent MSE alone for 9000 iterations (the training loss still falls at 3000)", MSE, False, 9000),
    "mse_6000_cosine": ("latent MSE alone for 6000 iterations, lr falling along a half cosine to 0",
                        MSE + ["--lr-decay", "cosine"], False, 6000),
    # Made before windowed inference (2026-11-26), mse_6000_cosine folders applied the refiner to
    # the whole view; the two below name the inference, so their folders mean one thing.
    "mse_6000_cosine_whole": ("mse_6000_cosine applied to the whole view at once (before 2026-11-26: every variant)",
                              MSE + ["--lr-decay", "cosine", "--inference", "whole"], False, 6000),
    "mse_6000_cosine_windows": ("mse_6000_cosine applied on windows of its 32² training crop, stride 16, averaged",
                                MSE + ["--lr-decay", "cosine", "--inference", "windows"], False, 6000),
    "mse_6000_cosine_mirror": ("mse_6000_cosine (windows) also on the training view's mirror image, against its "
                               "mirrored reference encoded again", MSE + ["--lr-decay", "cosine", "--augment", "mirror"],
                               False, 6000),
    "mse_12000_cosine_mirror": ("mse_6000_cosine_mirror with twice the steps: as many per view as mse_6000_cosine",
                                MSE + ["--lr-decay", "cosine", "--augment", "mirror"], False, 12000),
    # Several views make the smoothed crop loss jump between views' levels: patience 500 stopped
    # the three above at 4340, 4251 and 7437 steps, before their schedules ended. These run it all.
    "mse_6000_cosine_mirror_all": ("mse_6000_cosine_mirror without early stopping (the whole cosine period)",
                                   MSE + ["--lr-decay", "cosine", "--augment", "mirror", "--patience", "0"], False,
                                   6000),
    "mse_6000_cosine_dihedral_all": ("mse_6000_cosine_dihedral without early stopping (the whole cosine period)",
                                     MSE + ["--lr-decay", "cosine", "--augment", "dihedral", "--patience", "0"],
                                     False, 6000),
    "mse_6000_cosine_noise8_all": ("mse_6000_cosine on 8 renders of the training view (noise views), without early "
                                   "stopping (noise_views_8 stopped at 2538 of 3000 steps)",
                                   MSE + ["--lr-decay", "cosine", "--noise-views", "8", "--patience", "0"], False, 6000),
    "mse_6000_cosine_dihedral": ("mse_6000_cosine (windows) on the training view, its mirror image and both rolled "
                                 "by quarter turns (8 views)", MSE + ["--lr-decay", "cosine", "--augment", "dihedral"],
                                 False, 6000),
    # Regularisation and capacity on top of the preset's refiner (windows, one view, run as it stops).
    "mse_6000_cosine_no_dropout": ("mse_6000_cosine without dropout", MSE + ["--lr-decay", "cosine", "--dropout", "0"],
                                   False, 6000),
    "mse_6000_cosine_dropout_0.2": ("mse_6000_cosine with twice the dropout (0.2)",
                                    MSE + ["--lr-decay", "cosine", "--dropout", "0.2"], False, 6000),
    "mse_6000_cosine_expansion_8": ("mse_6000_cosine at half the width (expansion 8: 128 channels)",
                                    MSE + ["--lr-decay", "cosine", "--expansion", "8"], False, 6000),
    "mse_6000_cosine_expansion_32": ("mse_6000_cosine at twice the width (expansion 32: 512 channels; session 19)",
                                     MSE + ["--lr-decay", "cosine", "--expansion", "32"], False, 6000),
    "mse_6000_cosine_terms": ("mse_6000_cosine reading the transport terms Ie, Ia, Ic beside their toned sum "
                              "(--inputs terms; session 20)", MSE + ["--lr-decay", "cosine", "--inputs", "terms"],
                              False, 6000),
    # Whole-view training (InstanceNorm sees the statistics it sees at inference; no crops): a
    # 128² step costs ~16 crop steps, so 750 steps are twice the preset's pixels.
    "mse_750_cosine_whole_view": ("latent MSE on the whole view (no crops), 750 steps, lr falling along a half "
                                  "cosine: twice the pixels of mse_6000_cosine's 32² crops",
                                  MSE + ["--crop", "0", "--lr-decay", "cosine"], False, 750),
    "mse_375_cosine_whole_view": ("latent MSE on the whole view (no crops), 375 steps, lr falling along a half "
                                  "cosine: at 128² latents the pixels of mse_6000_cosine's 32² crops",
                                  MSE + ["--crop", "0", "--lr-decay", "cosine"], False, 375),
    # At 64² latents (Lamp, Living Room) a whole view is 4 crops: 3000 steps are twice the preset's pixels.
    "mse_3000_cosine_whole_view": ("latent MSE on the whole view (no crops), 3000 steps, lr falling along a half "
                                   "cosine: at 64² latents twice the pixels of mse_6000_cosine's 32² crops",
                                   MSE + ["--crop", "0", "--lr-decay", "cosine"], False, 3000),
    # Run with a binary whose early stopping followed the mean of per-view EMAs (session 12, not
    # kept: it stopped at 4199 where mse_6000_cosine_dihedral, the same options, stopped at 4251).
    "mse_6000_cosine_dihedral_per_view": ("mse_6000_cosine_dihedral with early stopping on the mean of per-view EMAs",
                                          MSE + ["--lr-decay", "cosine", "--augment", "dihedral"], False, 6000),
    # Another body (session 19): a two-level U-Net, a ~44-pixel view at a fifth of the multiply-adds.
    "mse_6000_cosine_unet": ("mse_6000_cosine with the U-Net body (--arch unet: widths 64, 128, 256, skip "
                             "connections)", MSE + ["--lr-decay", "cosine", "--arch", "unet"], False, 6000),
    # Patience 500 stopped mse_6000_cosine_unet at 3928 steps (its crop loss falls more slowly).
    "mse_6000_cosine_unet_all": ("mse_6000_cosine_unet without early stopping (the whole cosine period)",
                                 MSE + ["--lr-decay", "cosine", "--arch", "unet", "--patience", "0"], False, 6000),
    "mse_6000_cosine_unet_x32_all": ("mse_6000_cosine_unet_all twice as wide (expansion 32: widths 128, 256, 512)",
                                     MSE + ["--lr-decay", "cosine", "--arch", "unet", "--patience", "0",
                                            "--expansion", "32"], False, 6000),
    "mse_9000_cosine": ("latent MSE alone for 9000 iterations, lr falling along a half cosine to 0",
                        MSE + ["--lr-decay", "cosine"], False, 9000),
    "long": ("ours for 3000 iterations (the paper's count)", [], False, 3000),
    "lpips8_long": ("ours with 8² latent LPIPS crops (a quarter of the decode) for 3000 iterations", ["--lpips-crop", "8"],
                    False, 3000),
}


def with_mix(opts):
    """A variant's options with our mix's weights first, unless it sets a loss weight itself."""
    if opts is None or any(o in ("--w-ssim", "--w-lpips") for o in opts):
        return opts
    return MIX + opts


VARIANTS = {name: (what, with_mix(opts), drop, its) for name, (what, opts, drop, its) in VARIANTS.items()}


def iterations_of(a, name):
    return VARIANTS[name][3] or a.iterations




def train_variant(a, name, vdir):
    """A copy of the stage-1 fit with its refiner retrained by the variant's options (kept as is
    for 'default'). refine.done records what made the folder: a folder made otherwise (another
    fit, options or iterations) is an error, not silently reused."""
    _, opts, drop_rgb, _ = VARIANTS[name]
    iterations = iterations_of(a, name)
    stamp = json.dumps({"fit": os.path.abspath(a.fit), "options": opts, "drop_rgb": drop_rgb,
                        "iterations": None if opts is None else iterations})
    done = os.path.join(vdir, "refine.done")
    if os.path.exists(done):
        with open(done) as f:
            if f.read() != stamp:
                sys.exit(f"refiner_study: {vdir} was made with other settings ({done}); remove it to redo")
        return
    if opts is None and not os.path.exists(os.path.join(a.fit, "refiner.pt")):
        sys.exit(f"refiner_study: {a.fit} has no refiner.pt for the 'default' variant")
    if not os.path.isdir(vdir):
        tmp = vdir + ".tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        skip = ["checkpoint", "refiner_checkpoint.pt"] + (["refiner*.pt"] if opts is not None else [])
        shutil.copytree(a.fit, tmp, ignore=shutil.ignore_patterns(*skip))
        if drop_rgb:
            os.remove(os.path.join(tmp, "reference_rgb.exr"))
        os.replace(tmp, vdir)
    if opts is not None:
        resume = ["--resume"] if os.path.exists(os.path.join(vdir, "refiner_checkpoint.pt")) else []
        X.run_logged([a.bin, "--threads", str(a.threads), "refine", vdir, "--iterations", str(iterations), "--seed",
                      "0", "-q"] + opts + resume, os.path.join(vdir, "study.log"), "refiner_study")
    X.write_atomic(done, stamp)


def evaluate(a, vdir, kind):
    """Mean refined metrics of one edit sequence (the evaluated frames) rendered by the variant."""
    rows = X.edit_metrics(a.bin, a.threads, vdir, os.path.join(a.scene_dir, f"edits-{kind}.json"),
                          os.path.join(vdir, "edit_" + kind), a.spp, a.ref_spp, os.path.join(a.scene_dir, "refs"),
                          a.frames, os.path.join(vdir, "study.log"), "refiner_study")
    edited = [r for r in rows if int(r["frame"]) != 0]
    return {"lpips": X.mean(rows, "refined_rgb_lpips"), "mse_x100": X.mean(rows, "refined_rgb_mse_x100"),
            "edited_lpips": X.mean(edited, "refined_rgb_lpips"), "edited_mse_x100": X.mean(edited, "refined_rgb_mse_x100"),
            "edited_latent_mse": X.mean(edited, "refined_latent_mse"), "frames": [int(r["frame"]) for r in rows]}


def training_view(vdir):
    with open(os.path.join(vdir, "metrics.json")) as f:
        m = json.load(f)
    return {"lpips": m["refined"].get("rgb_lpips"), "mse_x100": m["refined"].get("rgb_mse_x100"),
            "reference": m.get("reference", "")}


def earlier_results(a):
    """Rows of earlier runs of this study whose variant folders are still there, so that study.md
    keeps every variant measured on the scene folder, not only this run's."""
    path = os.path.join(a.scene_dir, "refiner_study", "study.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        rows = json.load(f)
    start, stop, step = (int(v) for v in a.frames.split(":"))
    frames = list(range(start, stop + 1, step))
    return {name: r for name, r in rows.items()
            if name in VARIANTS and all(k in r and r[k].get("frames") == frames for k in a.kinds) and
            os.path.exists(os.path.join(a.scene_dir, "refiner_study", name, "refine.done"))}


def report(a, results):
    md = [f"# Refiner study on {a.scene_dir}", "",
          f"Stage-1 fit {a.fit}; refiner {a.iterations} iterations unless the variant names its own "
          "(the default variant: the fit's own refiner); "
          f"frames {a.frames} of each edit sequence at {a.spp} spp "
          f"against {a.ref_spp}-spp references. Mean refined LPIPS / MSE×100 (edit columns include frame 0, the "
          "training view, as the paper's means do; 'edited' excludes it). Choose by the edit means.", "",
          "| variant | what | " + " | ".join(a.kinds) + " | edited mean | edited latent MSE | training view |",
          "|---|---|" + "---|" * (len(a.kinds) + 3)]
    for name, r in results.items():
        cells = [f"{r[k]['lpips']:.4f} / {r[k]['mse_x100']:.4f}" for k in a.kinds]
        el = sum(r[k]["edited_lpips"] for k in a.kinds) / len(a.kinds)
        em = sum(r[k]["edited_mse_x100"] for k in a.kinds) / len(a.kinds)
        lat = [r[k].get("edited_latent_mse") for k in a.kinds]
        lat_cell = f"{sum(lat) / len(lat):.5f}" if None not in lat else "–"
        t = r["training_view"]
        md.append(f"| {name} | {VARIANTS[name][0]} | " + " | ".join(cells) + f" | {el:.4f} / {em:.4f} | {lat_cell} | "
                  f"{t['lpips']:.4f} / {t['mse_x100']:.4f} |")
    out = os.path.join(a.scene_dir, "refiner_study")
    X.write_atomic(os.path.join(out, "study.md"), "\n".join(md) + "\n")
    X.write_atomic(os.path.join(out, "study.json"), json.dumps(results, indent=1))
    print("\n".join(md))


def experiment_defaults(a):
    """Fills the unset --frames, --iterations, --ref-spp and --spp from the experiment's config."""
    path = os.path.join(os.path.dirname(os.path.abspath(a.scene_dir)), "experiment-config.json")
    c = None
    if os.path.exists(path):
        with open(path) as f:
            c = json.load(f)
    scene = os.path.basename(os.path.abspath(a.scene_dir))
    if c is None or scene not in X.SCENES:
        if None in (a.frames, a.iterations, a.ref_spp, a.spp):
            why = f"no experiment config at {path}" if c is None else f"'{scene}' is not an experiment scene"
            sys.exit(f"refiner_study: {why}; give --frames, --iterations, --ref-spp, --spp")
        return
    if a.frames is None:
        a.frames = X.frames_arg(c, scene, a.kinds[0])
    if a.iterations is None:
        a.iterations = c["refiner_iterations"]
    if a.ref_spp is None:
        a.ref_spp = X.ref_spp_of(c, scene)
    if a.spp is None:
        a.spp = c["spp"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene-dir", required=True, help="a scene folder of an experiment run")
    ap.add_argument("--fit", default=None, help="stage-1 fit folder to copy (default: <scene-dir>/fit_eac)")
    ap.add_argument("--variants", default="default,mse_only", help="comma-separated: " + ", ".join(VARIANTS))
    ap.add_argument("--kinds", default="camera,light,object")
    ap.add_argument("--frames", default=None, help="A:B:S (default: the frames the experiment evaluated)")
    ap.add_argument("--iterations", type=int, default=None, help="refiner steps (default: the experiment's)")
    ap.add_argument("--ref-spp", type=int, default=None, help="reference spp, the cache key (default: the experiment's)")
    ap.add_argument("--spp", type=int, default=None, help="latent spp (default: the experiment's)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--bin", default=os.path.join(X.ROOT, "build", "apps", "latentpt"))
    a = ap.parse_args()
    a.fit = a.fit or os.path.join(a.scene_dir, "fit_eac")
    a.kinds = a.kinds.split(",")
    experiment_defaults(a)
    if len(a.frames.split(":")) != 3:
        sys.exit("refiner_study: --frames expects A:B:S")
    for name in a.variants.split(","):
        if name not in VARIANTS:
            sys.exit(f"refiner_study: unknown variant '{name}' (have {', '.join(VARIANTS)})")
    results = earlier_results(a)
    for name in a.variants.split(","):
        vdir = os.path.join(a.scene_dir, "refiner_study", name)
        train_variant(a, name, vdir)
        results[name] = {k: evaluate(a, vdir, k) for k in a.kinds}
        results[name]["training_view"] = training_view(vdir)
        report(a, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
