#!/usr/bin/env python3
"""The paper's ablation (Table 1) and per-frame error plots as one command, on the scenes in
../shared/scenes, driving the latentpt binary. Python standard library only.

For each scene: three stage-1 fits to the TAESD3-encoded RGB reference (terms e, ea, eac; the
eac fit also trains the refiner), then every edit sequence scenes/<scene>/edits-<kind>.json
(camera, light, object; 60 frames) rendered by each fit with path-traced references (traced once
per sequence, shared through --reference-cache). Results under --out (default results/):

    <scene>/fit_<terms>/              latentpt fit folders
    <scene>/<kind>_<terms>/           render --edit folders (frames, metrics.csv)
    summary.md, summary.json          the ablation tables
    <scene>_<kind>_{lpips,dssim}.svg  per-frame plots (rendered vs refined vs ablations)
    report.html                       self-contained report (tables, plots, image grids)

--quick runs one scene at low resolution, few frames and low spp (CI: a few minutes) and exits
with status 1 unless the ablation ordering holds: +Ia and +Ic not worse than Ie alone (mean
decoded LPIPS over all edited frames, 5% tolerance for noise) and the refiner not worse than the
rendered latent on the training view (metrics.json).

Also: convergence of latent D-SSIM and decoded LPIPS with latent spp (1..1024) on the training
view and a novel view (the camera edit's last keyframe), <scene>_convergence_<view>.svg.

The paper's baseline (a classic non-negative render in [0, 1) + logit + the same refiner) is a
fourth fit (--param classic --tone logit --terms e) in every table.

Equal-error runtime: `latentpt bench --equal-error <fitdir>` on the eac fit, its output kept in
summary.md.
"""
import argparse
import base64
import csv
import html
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# name -> (scene file under <shared>/scenes, -D overrides)
# scene: (file under ../shared/scenes, -D defines, default reference spp). The reference traces
# dominate the budget (docs/results.md "Budget"): at 256² a 512-spp cbox frame took 22 s on the
# 2-core machine, 180 frames 66 min; dining-room frames cost ~2x cbox's, veach-bidir ~1.2x.
SCENES = {
    "cbox-specular": ("cbox/cbox_specular.xml", [], 256),
    "veach-bidir": ("veach-bidir/scene_v3.xml", [], 256),
    "dining-room": ("dining-room/scene_diffuse.xml", [], 128),
}
KINDS = ["camera", "light", "object"]
CONFIGS = [("e", "Ĩe"), ("ea", "+Ĩa"), ("eac", "+Ĩc"), ("eac+refiner", "+refiner"),
           ("baseline", "baseline [0,1)+logit"), ("baseline+refiner", "baseline + refiner")]
# Fits: name -> (terms, extra fit arguments, trains a refiner). The baseline is the paper's
# comparison: a classic non-negative 16-channel render in [0, 1), logit to latent space
# (--param classic --tone logit), Ĩe only, the same refiner; its lr is raised to 1.0 because
# its radiances must grow from ~0.1 to ~10 (measured on the Cornell box: Huber 2.6 at lr 0.05,
# 1.3 at lr 1.0 after 600 iterations).
FITS = {"e": ("e", [], False, 0.05), "ea": ("ea", [], False, 0.05), "eac": ("eac", [], True, 0.05),
        "baseline": ("e", ["--param", "classic", "--tone", "logit"], True, 1.0)}


def run(cmd, log):
    t0 = time.time()
    with open(log, "a") as f:
        f.write("$ " + " ".join(cmd) + "\n")
        f.flush()
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit(f"experiment: command failed ({r.returncode}), see {log}: {' '.join(cmd)}")
    return time.time() - t0


def read_metrics(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def mean(rows, key):
    vals = [float(r[key]) for r in rows if r.get(key, "") not in ("", None)]
    return sum(vals) / len(vals) if vals else float("nan")


def svg_plot(title, series, ylabel, width=480, height=260):
    """A minimal line chart: series = [(label, colour, [y per frame])]."""
    pad_l, pad_r, pad_t, pad_b = 56, 110, 28, 36
    ys = [y for _, _, v in series for y in v if y == y]
    if not ys:
        return ""
    lo, hi = min(0.0, min(ys)), max(ys) * 1.05 or 1.0
    n = max(len(v) for _, _, v in series)
    sx = lambda i: pad_l + (width - pad_l - pad_r) * (i / max(1, n - 1))
    sy = lambda y: height - pad_b - (height - pad_t - pad_b) * ((y - lo) / (hi - lo))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="11">',
           f'<text x="{width / 2}" y="16" text-anchor="middle" font-size="13">{html.escape(title)}</text>',
           f'<line x1="{pad_l}" y1="{height - pad_b}" x2="{width - pad_r}" y2="{height - pad_b}" stroke="black"/>',
           f'<line x1="{pad_l}" y1="{pad_t}" x2="{pad_l}" y2="{height - pad_b}" stroke="black"/>',
           f'<text x="{(pad_l + width - pad_r) / 2}" y="{height - 6}" text-anchor="middle">frame</text>',
           f'<text x="14" y="{height / 2}" transform="rotate(-90 14 {height / 2})" text-anchor="middle">{html.escape(ylabel)}</text>']
    for k in range(5):
        y = lo + (hi - lo) * k / 4
        out.append(f'<text x="{pad_l - 4}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:.3g}</text>')
    for j, (label, colour, v) in enumerate(series):
        pts = " ".join(f"{sx(i):.1f},{sy(y):.1f}" for i, y in enumerate(v) if y == y)
        out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="1.6" points="{pts}"/>')
        out.append(f'<text x="{width - pad_r + 8}" y="{pad_t + 14 * j + 10}" fill="{colour}">{html.escape(label)}</text>')
    out.append("</svg>")
    return "\n".join(out)


def img_tag(path, width=160):
    if not os.path.exists(path):
        return "<td>(missing)</td>"
    with open(path, "rb") as f:
        data = base64.b64encode(f.read()).decode()
    return f'<td><img width="{width}" src="data:image/png;base64,{data}"/></td>'


def write_atomic(path, text):
    """Writes text to path through a temporary file and a rename: never a truncated result."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def write_outputs(a, summary, failures, image_res, fit_its, ref_its, frames):
    """summary.md/json, the SVG plots and report.html for the scenes finished so far; called
    after every scene so an interrupted multi-scene run keeps its finished scenes' tables."""
    # Tables (markdown) and plots.
    colours = {"e": "#999999", "ea": "#1f77b4", "eac": "#2ca02c", "eac+refiner": "#d62728", "baseline": "#9467bd",
               "baseline+refiner": "#e377c2"}
    md = ["# latentpt experiment summary", "",
          f"settings: image {image_res}² (latents {image_res // 8}²), reference spp per scene below, stage 1 {fit_its} iterations, "
          f"refiner {ref_its} iterations, frames {frames or 'as in the edit files'}, edited latents {a.spp} spp", ""]
    for scene, s in summary.items():
        t = s["training_view"]
        md += [f"## {scene}", "", f"References: {s.get('ref_spp')} spp.", "", "Training view (decoded vs reference): " +
               ", ".join(f"{k} LPIPS {t[k].get('rgb_lpips', float('nan')):.4f} / MSE×100 {t[k].get('rgb_mse_x100', float('nan')):.4f}"
                         for k in ("rendered", "refined", "vae_roundtrip") if k in t), "",
               "| edit | config | LPIPS | MSE×100 | latent D-SSIM |", "|---|---|---|---|---|"]
        for kind, table in s["edits"].items():
            for key, label in CONFIGS:
                r = table[key]
                md.append(f"| {kind} | {label} | {r['rgb_lpips']:.4f} | {r['rgb_mse_x100']:.4f} | {r['latent_dssim']:.4f} |")
            for metric, ylabel in (("lpips", "LPIPS (decoded)"), ("dssim", "D-SSIM (latent)")):
                svg = svg_plot(f"{scene}, {kind} edit", [(label, colours[key], table[key]["per_frame_" + metric]) for key, label in CONFIGS], ylabel)
                write_atomic(os.path.join(a.out, f"{scene}_{kind}_{metric}.svg"), svg)
        if "convergence" in s:
            md += ["", "Convergence of the eac fit vs latent spp (latent D-SSIM / decoded LPIPS; rendered → refined):", "",
                   "| view | spp | D-SSIM | refined D-SSIM | LPIPS | refined LPIPS |", "|---|---|---|---|---|---|"]
            for view, by_spp in s["convergence"].items():
                for spp, r in by_spp.items():
                    md.append(f"| {view} | {spp} | {r['latent_dssim']:.4f} | {r['refined_latent_dssim']:.4f} | {r['rgb_lpips']:.4f} | {r['refined_rgb_lpips']:.4f} |")
                svg = svg_plot(f"{scene}, {view} view: error vs spp ({', '.join(map(str, by_spp))})",
                               [(lab, col, [r[k] for r in by_spp.values()]) for k, lab, col in
                                (("latent_dssim", "D-SSIM", "#1f77b4"), ("refined_latent_dssim", "D-SSIM refined", "#2ca02c"),
                                 ("rgb_lpips", "LPIPS", "#ff7f0e"), ("refined_rgb_lpips", "LPIPS refined", "#d62728"))], "error")
                write_atomic(os.path.join(a.out, f"{scene}_convergence_{view}.svg"), svg)
        if "wall_seconds" in s:
            md += ["", f"Wall time of this run for {scene}: {s['wall_seconds'] / 60:.1f} min (budget 120 min; " +
                   ", ".join(f"{k} {v / 60:.1f}" for k, v in s["stages"].items()) + " min; results reused from an earlier run in --out count as ~0)"]
        if "equal_error" in s:
            md += ["", "Equal-error runtime (`latentpt bench --equal-error`, this machine, timings from one process):", "", "```",
                   s["equal_error"].rstrip(), "```"]
        md.append("")
    if failures:
        md += ["## Ordering check failed", ""] + [f"- {x}" for x in failures]
    write_atomic(os.path.join(a.out, "summary.md"), "\n".join(md) + "\n")
    write_atomic(os.path.join(a.out, "summary.json"), json.dumps(summary, indent=1))

    # Self-contained HTML report.
    h = ["<!doctype html><html><head><meta charset='utf-8'><title>latentpt experiments</title>",
         "<style>body{font-family:sans-serif;margin:2em;max-width:1200px} table{border-collapse:collapse} "
         "td,th{border:1px solid #ccc;padding:3px 8px} img{image-rendering:pixelated}</style></head><body>",
         "<h1>latentpt experiments</h1>", f"<p>{html.escape(md[2])}</p>"]
    for scene, s in summary.items():
        h.append(f"<h2>{html.escape(scene)}</h2><table><tr><th>edit</th><th>config</th><th>LPIPS</th><th>MSE×100</th><th>latent D-SSIM</th></tr>")
        for kind, table in s["edits"].items():
            for key, label in CONFIGS:
                r = table[key]
                h.append(f"<tr><td>{kind}</td><td>{html.escape(label)}</td><td>{r['rgb_lpips']:.4f}</td><td>{r['rgb_mse_x100']:.4f}</td>"
                         f"<td>{r['latent_dssim']:.4f}</td></tr>")
        h.append("</table>")
        for view in s.get("convergence", {}):
            with open(os.path.join(a.out, f"{scene}_convergence_{view}.svg")) as f:
                h.append(f.read())
        for kind in s["edits"]:
            for metric in ("lpips", "dssim"):
                with open(os.path.join(a.out, f"{scene}_{kind}_{metric}.svg")) as f:
                    h.append(f.read())
            n = len(s["edits"][kind]["e"]["per_frame_lpips"])
            h.append(f"<h3>{kind}: reference / Ĩe / +Ĩa+Ĩc / +refiner / baseline + refiner</h3><table>")
            for i in sorted({0, n // 2, n - 1}):
                d = os.path.join(a.out, scene)
                h.append("<tr><td>frame %d</td>" % i + img_tag(os.path.join(d, f"{kind}_eac", f"frame_{i:04d}_reference.png")) +
                         img_tag(os.path.join(d, f"{kind}_e", f"frame_{i:04d}.png")) +
                         img_tag(os.path.join(d, f"{kind}_eac", f"frame_{i:04d}_rendered.png")) +
                         img_tag(os.path.join(d, f"{kind}_eac", f"frame_{i:04d}.png")) +
                         img_tag(os.path.join(d, f"{kind}_baseline", f"frame_{i:04d}.png")) + "</tr>")
            h.append("</table>")
    if failures:
        h.append("<h2>Ordering check failed</h2><ul>" + "".join(f"<li>{html.escape(x)}</li>" for x in failures) + "</ul>")
    h.append("</body></html>")
    write_atomic(os.path.join(a.out, "report.html"), "\n".join(h))
    return md


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="one scene, small and short; checks the ablation ordering (CI)")
    ap.add_argument("--scenes", default=None, help="comma-separated subset of " + ", ".join(SCENES))
    ap.add_argument("--out", default=os.path.join(ROOT, "results"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "latentpt"))
    ap.add_argument("--shared", default=os.environ.get("LATENTPT_SHARED", os.path.join(ROOT, "..", "shared")))
    ap.add_argument("--image-res", type=int, default=None, help="square RGB resolution (latents: 1/8)")
    ap.add_argument("--frames", type=int, default=None, help="frames per edit sequence (default: the files', 60)")
    ap.add_argument("--ref-spp", type=int, default=None, help="samples per pixel of the RGB references (default: per scene, 128-256)")
    ap.add_argument("--fit-iterations", type=int, default=None)
    ap.add_argument("--refiner-iterations", type=int, default=None)
    ap.add_argument("--spp", type=int, default=64, help="latent samples per pixel of the edited frames")
    ap.add_argument("--redo", action="store_true", help="recompute everything (default: reuse finished fits and edit renders in --out)")
    a = ap.parse_args()
    q = a.quick
    image_res = a.image_res or (128 if q else 256)
    fit_its = a.fit_iterations or (300 if q else 1500)
    ref_its = a.refiner_iterations or (100 if q else 1000)
    frames = a.frames or (3 if q else None)
    spp_list = [1, 4, 16, 64] if q else [1, 4, 16, 64, 256, 1024]
    scenes = a.scenes.split(",") if a.scenes else (["cbox-specular"] if q else list(SCENES))
    for s in scenes:
        if s not in SCENES:
            sys.exit(f"experiment: unknown scene '{s}' (have {', '.join(SCENES)})")
    if not os.path.exists(a.bin):
        sys.exit(f"experiment: {a.bin} not found (bash scripts/build.sh)")
    os.makedirs(a.out, exist_ok=True)
    log = os.path.join(a.out, "experiment.log")
    summary = {}
    failures = []
    for scene in scenes:
        rel, defines, scene_ref_spp = SCENES[scene]
        ref_spp = a.ref_spp or (32 if q else scene_ref_spp)
        scene_file = os.path.join(a.shared, "scenes", rel)
        if not os.path.exists(scene_file):
            print(f"experiment: {scene_file} not found (set LATENTPT_SHARED or --shared)", file=sys.stderr)
            return 77  # ctest's SKIP_RETURN_CODE
        sdir = os.path.join(a.out, scene)
        os.makedirs(sdir, exist_ok=True)
        times = {}
        stage_t0 = scene_t0 = time.time()
        stages = {}  # wall seconds per stage of this run (results reused from --out cost ~0)
        for name, (terms, extra, refine, lr) in FITS.items():
            fit_dir = os.path.join(sdir, "fit_" + name)
            cmd = [a.bin, "fit", scene_file, "--encode", "--encode-res", f"{image_res}x{image_res}", "--ref-spp", str(ref_spp),
                   "--iterations", str(fit_its), "--spp", "4", "--lr", str(lr), "--lr-period", str(fit_its), "--final-spp", "64",
                   "--terms", terms, "-q", "--out", fit_dir] + extra
            cmd += ["--refiner-iterations", str(ref_its)] if refine else ["--no-refiner"]
            for d in defines:
                cmd += ["-D", d]
            done = os.path.exists(os.path.join(fit_dir, "fit.json")) and (not refine or os.path.exists(os.path.join(fit_dir, "metrics.json")))
            if done and not a.redo:  # a finished fit from an interrupted or earlier run
                print(f"[{scene}] fit {name}: done already ({fit_dir})", flush=True)
                continue
            print(f"[{scene}] fit {name} ...", flush=True)
            times["fit_" + name] = run(cmd, log)
        with open(os.path.join(sdir, "fit_eac", "metrics.json")) as f:
            train = json.load(f)
        stages["fits"] = time.time() - stage_t0
        stage_t0 = time.time()
        summary[scene] = {"training_view": train, "seconds": times, "stages": stages, "ref_spp": ref_spp, "edits": {}}
        r_l, f_l = train["rendered"].get("rgb_lpips"), train["refined"].get("rgb_lpips")
        if r_l is not None and f_l is not None and f_l > r_l * 1.0001:
            failures.append(f"{scene}: refiner worse than the rendered latent on the training view (LPIPS {f_l:.4f} > {r_l:.4f})")
        for kind in KINDS:
            edit_file = os.path.join(ROOT, "scenes", scene, f"edits-{kind}.json")
            if frames:
                with open(edit_file) as f:
                    e = json.load(f)
                e["frames"] = frames
                edit_file = os.path.join(sdir, f"edits-{kind}.json")
                with open(edit_file, "w") as f:
                    json.dump(e, f)
            rows = {}
            for name in FITS:
                out = os.path.join(sdir, f"{kind}_{name}")
                mcsv = os.path.join(out, "metrics.csv")
                if os.path.exists(mcsv) and not a.redo and len(read_metrics(mcsv)) == (frames or 60):
                    rows[name] = read_metrics(mcsv)
                    continue
                print(f"[{scene}] {kind} edit with fit {name} ...", flush=True)
                run([a.bin, "render", os.path.join(sdir, "fit_" + name), "--edit", edit_file, "--reference", "--ref-spp", str(ref_spp),
                     "--reference-cache", os.path.join(sdir, "refs"), "--spp", str(a.spp), "-q", "--out", out], log)
                rows[name] = read_metrics(os.path.join(out, "metrics.csv"))
            table = {}
            for key, _ in CONFIGS:
                src, pre = (rows[key[:-len("+refiner")]], "refined_") if key.endswith("+refiner") else (rows[key], "")
                table[key] = {m: mean(src, pre + m) for m in ("rgb_lpips", "rgb_mse_x100", "latent_dssim", "latent_mse")}
                table[key]["per_frame_lpips"] = [float(r[pre + "rgb_lpips"] or "nan") for r in src]
                table[key]["per_frame_dssim"] = [float(r[pre + "latent_dssim"] or "nan") for r in src]
            summary[scene]["edits"][kind] = table
            base = table["e"]["rgb_lpips"]
            for key in ("ea", "eac"):
                if table[key]["rgb_lpips"] > base * 1.05:
                    failures.append(f"{scene}/{kind}: {key} LPIPS {table[key]['rgb_lpips']:.4f} worse than e alone {base:.4f}")

        stages["edits (references + renders)"] = time.time() - stage_t0
        stage_t0 = time.time()
        # Convergence: latent D-SSIM and decoded LPIPS of the eac fit (rendered and refined) vs
        # spp, on the training view and on the camera edit's last keyframe (a novel view).
        with open(os.path.join(ROOT, "scenes", scene, "edits-camera.json")) as f:
            cam = json.load(f)["camera"]
        orbit = dict(cam["orbit"])
        for k in ("azimuth", "elevation"):  # the last keyframe, held
            if isinstance(orbit.get(k), list):
                orbit[k] = orbit[k][-1]
        novel = {"frames": 1, "camera": {"orbit": orbit}}
        views = {"training": {"frames": 1}, "novel": novel}
        conv = {}
        for view, spec in views.items():
            vfile = os.path.join(sdir, f"view-{view}.json")
            with open(vfile, "w") as f:
                json.dump(spec, f)
            conv[view] = {}
            for spp in spp_list:
                out = os.path.join(sdir, f"conv_{view}_{spp}")
                print(f"[{scene}] convergence {view} view, {spp} spp ...", flush=True)
                run([a.bin, "render", os.path.join(sdir, "fit_eac"), "--edit", vfile, "--reference", "--ref-spp", str(ref_spp),
                     "--reference-cache", os.path.join(sdir, "refs"), "--spp", str(spp), "-q", "--out", out], log)
                r = read_metrics(os.path.join(out, "metrics.csv"))[0]
                conv[view][spp] = {k: float(r[k] or "nan") for k in ("latent_dssim", "rgb_lpips", "refined_latent_dssim", "refined_rgb_lpips")}
        summary[scene]["convergence"] = conv
        stages["convergence"] = time.time() - stage_t0
        stage_t0 = time.time()
        # Equal-error runtime: latent renderer vs RGB path tracing (+ VAE), timed in one process.
        print(f"[{scene}] equal-error runtime ...", flush=True)
        r = subprocess.run([a.bin, "bench", "--equal-error", os.path.join(sdir, "fit_eac")], capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"experiment: bench --equal-error failed: {r.stderr}")
        summary[scene]["equal_error"] = r.stdout
        stages["equal-error benchmark"] = time.time() - stage_t0
        summary[scene]["wall_seconds"] = time.time() - scene_t0
        md = write_outputs(a, summary, failures, image_res, fit_its, ref_its, frames)  # the last scene's call writes the final files

    print("\n".join(md))
    print(f"wrote {a.out}/summary.md, summary.json, report.html and plots")
    if failures:
        print("experiment: ordering check FAILED:\n  " + "\n  ".join(failures), file=sys.stderr)
        return 1 if q else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
