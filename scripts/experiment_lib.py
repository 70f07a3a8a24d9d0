"""What the experiment workflow (workflow/Snakefile) computes and reports: the scenes, fits and
edit sequences of the paper's ablation, the latentpt command of every job, and the tables,
plots and HTML report built from the finished outputs (Table 1 itself: paper_table.py, whose
names it re-exports). Python standard library only; shared by the Snakefile,
scripts/experiment.py (its front) and the tests."""
import base64
import concurrent.futures
import csv
import html
import json
import os
import shlex
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_table import (NOISE_MEASURES, PAPER_NAMES, PAPER_TABLE1, TABLE1_COLUMNS,  # noqa: E402,F401 (re-exported)
                         TABLE1_NOTE, TABLE1_TARGETS, independent_table1_summary, misses_line, noise_table1_entry, table1, table1_html, table1_rows)

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


# --second-references (docs/metrics.md "Reference noise"): every scored frame's reference traced
# again with this --ref-seed (render --edit of the eac fit into <scene>/noise_seed1/<kind>), then
# scripts/reference_noise.py --ablation, for Table 1 against an independent reference.
NOISE_SEED = 1
NOISE_DIR = f"noise_seed{NOISE_SEED}"


def read_metrics(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def mean(rows, key):
    """The mean of column `key` over every row; NaN when any row lacks it (a frame scored without
    LPIPS weights): a mean over some of the frames would pass for one over all of them."""
    vals = [float(r[key]) for r in rows if r.get(key, "") not in ("", None)]
    return sum(vals) / len(vals) if vals and len(vals) == len(rows) else float("nan")


def svg_plot(title, series, ylabel, xlabel="frame", xticks=None, width=480, height=260):
    """A minimal line chart: series = [(label, colour, [y per x position])], each value marked by
    a dot. The x axis is the frame index, or the labels `xticks` (one per position, e.g. spp)
    under `xlabel`; at most 12 of them are written."""
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
           f'<text x="{(pad_l + width - pad_r) / 2}" y="{height - 6}" text-anchor="middle">{html.escape(xlabel)}</text>',
           f'<text x="14" y="{height / 2}" transform="rotate(-90 14 {height / 2})" text-anchor="middle">{html.escape(ylabel)}</text>']
    ticks = list(xticks) if xticks else [str(i) for i in range(n)]
    every = -(-len(ticks) // 12)  # ceil: a 60-frame sequence gets every 5th
    for i, t in enumerate(ticks):
        if i % every:
            continue
        out.append(f'<text x="{sx(i):.1f}" y="{height - pad_b + 13}" text-anchor="middle">{html.escape(str(t))}</text>')
    for k in range(5):
        y = lo + (hi - lo) * k / 4
        out.append(f'<text x="{pad_l - 4}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:.3g}</text>')
    for j, (label, colour, v) in enumerate(series):
        pts = " ".join(f"{sx(i):.1f},{sy(y):.1f}" for i, y in enumerate(v) if y == y)
        out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="1.6" points="{pts}"/>')
        out += [f'<circle cx="{sx(i):.1f}" cy="{sy(y):.1f}" r="2.5" fill="{colour}"/>' for i, y in enumerate(v) if y == y]
        out.append(f'<text x="{width - pad_r + 8}" y="{pad_t + 14 * j + 10}" fill="{colour}">{html.escape(label)}</text>')
    out.append("</svg>")
    return "\n".join(out)


def thumbnail(path, width):
    """(MIME type, bytes) of the image at `path` shrunk to `width` pixels, by oiiotool (a 1024²
    frame is ~1.5 MB as PNG, its 320-pixel JPEG ~15 kB, the same bytes every run); the file itself
    where oiiotool fails."""
    with tempfile.TemporaryDirectory() as d:
        small = os.path.join(d, "thumbnail.jpg")
        try:
            r = subprocess.run(["oiiotool", "--nosoftwareattrib", path, "--resize:filter=box", f"{width}x0",
                                "--compression", "jpeg:90", "-o", small], capture_output=True)
            if r.returncode == 0:
                with open(small, "rb") as f:
                    return "image/jpeg", f.read()
        except OSError:
            pass
    with open(path, "rb") as f:
        return "image/png", f.read()


def thumbnails(paths, width):
    """{path: thumbnail(path, width)} for the existing files among `paths`, one oiiotool per core at
    a time (the preset's report shrinks 81 frames: ~60 s one after the other on 2 cores)."""
    paths = sorted({p for p in paths if os.path.exists(p)})
    with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return dict(zip(paths, pool.map(lambda p: thumbnail(p, width), paths)))


def img_tag(path, link, width=160, made=None):
    """A table cell with the image at `path` embedded at `width` pixels (twice that stored, for
    high-density screens), linking to the full image at `link` (relative to the report); `made`:
    thumbnails() of it at that size, if already made."""
    if not os.path.exists(path):
        return "<td>(missing)</td>"
    mime, data = (made or {}).get(path) or thumbnail(path, 2 * width)
    return (f'<td><a href="{html.escape(link)}"><img width="{width}" '
            f'src="data:{mime};base64,{base64.b64encode(data).decode()}"/></a></td>')


def write_atomic(path, text):
    """Writes text to path through a temporary file and a rename: never a truncated result."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def run_logged(cmd, log, who):
    """Runs `cmd` with its output appended to `log` (after the command line); on failure exits,
    naming `who` and the log, as the study scripts do."""
    with open(log, "a") as f:
        f.write("$ " + " ".join(cmd) + "\n")
        f.flush()
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit(f"{who}: command failed (exit {r.returncode}), see {log}: {' '.join(cmd)}")


def settings_line(c):
    """The run's settings in one sentence (summary.md, report.html)."""
    image_res, fit_its, ref_its, frames = c["image_res"], c["fit_iterations"], c["refiner_iterations"], c["frames"]
    step = c.get("frame_step", 1)
    dropout = f", dropout {c['refiner_dropout']:g}" if c.get("refiner_dropout") is not None else ""
    dropout += ", emitter refiner" if c.get("refiner_emitters") else ""
    return (f"settings: image {'per scene (below)' if c.get('scene_res') else f'{image_res}² (latents {image_res // 8}²)'}, "
            "reference spp per scene below, "
            f"stage 1 {fit_its} iterations, refiner {ref_its} iterations (lr decay {c.get('refiner_lr_decay', 'none')}"
            f"{', latent target ' + c['refiner_latent_target'] if c.get('refiner_latent_target', 'encoded') != 'encoded' else ''}"
            f"{dropout}), "
            f"parameterisation {c.get('param', 'code')}, emission decay {c.get('emission_decay', 0):g}, "
            f"emitter response decay {c.get('emitter_response_decay', 0):g}"
            f"{', light exposures ' + ','.join(repr(float(k)) for k in c['exposures']) if c.get('exposures') else ''}, "
            f"frames {frames or 'as in the edit files'}"
            f"{f', every {step}th evaluated' if step > 1 else ''}, edited latents {c['spp']} spp")


def write_outputs(out, c, summary, failures, timings, noise=None):
    """summary.md/json, the SVG plots and report.html under `out`. summary.json holds results
    only (no timings: a cluster run and a local run of one config give the same file);
    timings.json holds the job times. noise: reference_noise.py's result per scene
    (--second-references), for Table 1 against the independent references."""
    # Tables (markdown) and plots.
    colours = {"e": "#999999", "ea": "#1f77b4", "eac": "#2ca02c", "eac+refiner": "#d62728", "baseline": "#9467bd",
               "baseline+refiner": "#e377c2"}
    configs, step = configs_of(c), c.get("frame_step", 1)
    md = ["# latentpt experiment summary", "", settings_line(c), ""]
    facts = {}  # per scene: the sentences and the equal-error table report.html repeats
    for scene, s in summary.items():
        t = s["training_view"]
        res = image_res_of(c, scene)
        facts[scene] = {"lines": [
            f"Image {res}² (latents {res // 8}²). References: training view {training_ref_spp_of(c, scene)} spp, "
            f"edited frames {s.get('ref_spp')} spp.", "Training view (decoded vs reference): " +
            ", ".join(f"{k} LPIPS {t[k].get('rgb_lpips', float('nan')):.4f} / MSE×100 {t[k].get('rgb_mse_x100', float('nan')):.4f}"
                      for k in ("rendered", "refined", "vae_roundtrip") if k in t)]}
        md += [f"## {scene}", "", facts[scene]["lines"][0], "", facts[scene]["lines"][1], "",
               "| edit | config | LPIPS | MSE×100 | latent D-SSIM |", "|---|---|---|---|---|"]
        for kind, table in s["edits"].items():
            for key, label in configs:
                r = table[key]
                md.append(f"| {kind} | {label} | {r['rgb_lpips']:.4f} | {r['rgb_mse_x100']:.4f} | {r['latent_dssim']:.4f} |")
            for metric, ylabel in (("lpips", "LPIPS (decoded)"), ("dssim", "D-SSIM (latent)")):
                svg = svg_plot(f"{scene}, {kind} edit: {ylabel}",
                               [(label, colours[key], table[key]["per_frame_" + metric]) for key, label in configs],
                               ylabel, xlabel="frame of the edit sequence", xticks=sequence_frames(table) if step > 1 else None)
                write_atomic(os.path.join(out, f"{scene}_{kind}_{metric}.svg"), svg)
        if s.get("convergence"):  # conv_views=[] runs none
            md += ["", "Convergence of the eac fit vs latent spp (latent D-SSIM / decoded LPIPS; rendered → refined):", "",
                   "| view | spp | D-SSIM | refined D-SSIM | LPIPS | refined LPIPS |", "|---|---|---|---|---|---|"]
            for view, by_spp in s["convergence"].items():
                for spp, r in by_spp.items():
                    md.append(f"| {view} | {spp} | {r['latent_dssim']:.4f} | {r['refined_latent_dssim']:.4f} | {r['rgb_lpips']:.4f} | {r['refined_rgb_lpips']:.4f} |")
                svg = svg_plot(f"{scene}, {view} view: error vs spp ({', '.join(map(str, by_spp))})",
                               [(lab, col, [r[k] for r in by_spp.values()]) for k, lab, col in
                                (("latent_dssim", "D-SSIM", "#1f77b4"), ("refined_latent_dssim", "D-SSIM refined", "#2ca02c"),
                                 ("rgb_lpips", "LPIPS", "#ff7f0e"), ("refined_rgb_lpips", "LPIPS refined", "#d62728"))],
                               "D-SSIM (latent), LPIPS (decoded)", xlabel="latent samples per pixel (one position each)",
                               xticks=list(by_spp))
                write_atomic(os.path.join(out, f"{scene}_convergence_{view}.svg"), svg)
        t = timings.get(scene, {})
        if t.get("stages"):
            facts[scene]["lines"].append(
                f"Job time for {scene} (sum over its jobs, from Snakemake's benchmarks; jobs that ran in "
                "parallel overlap, finished jobs reused from an earlier run count once): " +
                ", ".join(f"{k} {v / 60:.1f} min" for k, v in t["stages"].items()))
            md += ["", facts[scene]["lines"][-1]]
        if t.get("equal_error"):
            facts[scene]["equal_error"] = t["equal_error"].rstrip()
            md += ["", "Equal-error runtime (`latentpt bench --equal-error`, this machine, timings from one process):", "", "```",
                   facts[scene]["equal_error"], "```"]
        md.append("")
    has_table1 = all(sc in PAPER_TABLE1 and set(s["edits"]) == set(KINDS) and "eac" in fits_of(c) for sc, s in summary.items())
    if has_table1:
        t1, misses = table1(c, summary)
        md += ["## Table 1 layout: ours (paper's), LPIPS / MSE×100", "", TABLE1_NOTE, ""] + t1
        md += ["", misses_line(misses, f"Targets (issue 16): {TABLE1_TARGETS}"), ""]
        md += [f"- {x}" for x in misses]
        md.append("")
    if noise:
        md += independent_table1_lines(c, noise)
    if failures:
        md += ["## Ordering check failed", ""] + [f"- {x}" for x in failures]
    write_atomic(os.path.join(out, "summary.md"), "\n".join(md) + "\n")
    results = {"scenes": summary, "failures": failures}
    if noise:
        results["reference_noise"] = noise
    write_atomic(os.path.join(out, "summary.json"), json.dumps(results, indent=1))
    write_atomic(os.path.join(out, "timings.json"), json.dumps(timings, indent=1))

    write_report(out, c, summary, failures, facts, has_table1, noise)
    return md


def write_report(out, c, summary, failures, facts, has_table1, noise):
    """report.html: write_outputs' tables, the plots and each sequence's frames, self-contained
    (small images embedded, each linking to its full-size file beside the report)."""
    configs = configs_of(c)
    made = thumbnails([os.path.join(out, rel) for scene, s in summary.items() for kind in s["edits"]
                       for _, cells in strip_rows(s["edits"][kind], strip_columns(fits_of(c)), scene, kind)
                       for rel in cells], 320)
    h = ["<!doctype html><html><head><meta charset='utf-8'><title>latentpt experiments</title>",
         "<style>body{font-family:sans-serif;margin:2em;max-width:1200px} table{border-collapse:collapse} "
         "td,th{border:1px solid #ccc;padding:3px 8px} .miss{color:#c00;font-weight:bold} "
         ".paper{color:#888;font-size:90%} .t1 td{white-space:nowrap} pre{font-size:85%}</style></head><body>",
         "<h1>latentpt experiments</h1>", f"<p>{html.escape(settings_line(c))}</p>"]
    if has_table1:
        h += table1_html(c, summary, "Table 1 layout (against the experiment's references)")
    independent = independent_table1_summary(noise) if noise else None
    if independent:
        h += table1_html(c, independent, "Table 1 against an independent reference per frame "
                         "(--second-references; MSE×100 less the reference's noise)")
    for scene, s in summary.items():
        h.append(f"<h2>{html.escape(scene)}</h2>" + "".join(f"<p>{html.escape(x)}</p>" for x in facts[scene]["lines"]))
        h.append("<table><tr><th>edit</th><th>config</th><th>LPIPS</th><th>MSE×100</th><th>latent D-SSIM</th></tr>")
        for kind, table in s["edits"].items():
            for key, label in configs:
                r = table[key]
                h.append(f"<tr><td>{kind}</td><td>{html.escape(label)}</td><td>{r['rgb_lpips']:.4f}</td><td>{r['rgb_mse_x100']:.4f}</td>"
                         f"<td>{r['latent_dssim']:.4f}</td></tr>")
        h.append("</table>")
        for view in s.get("convergence", {}):
            with open(os.path.join(out, f"{scene}_convergence_{view}.svg")) as f:
                h += [f"<h3>Convergence of the eac fit, {view} view</h3><div>", f.read(), "</div>"]
        if facts[scene].get("equal_error"):
            h += ["<h3>Equal-error runtime (<code>latentpt bench --equal-error</code>, this machine)</h3>",
                  f"<pre>{html.escape(facts[scene]['equal_error'])}</pre>"]
        for kind in s["edits"]:
            h.append(f"<h3>{kind} edit</h3><div>")
            for metric in ("lpips", "dssim"):
                with open(os.path.join(out, f"{scene}_{kind}_{metric}.svg")) as f:
                    h.append(f.read())
            columns = strip_columns(fits_of(c))
            h.append("</div><table><tr><th></th>" + "".join(f"<th>{html.escape(label)}</th>" for label, _, _ in columns) + "</tr>")
            for i, cells in strip_rows(s["edits"][kind], columns, scene, kind):
                tags = "".join(img_tag(os.path.join(out, rel), rel, made=made) for rel in cells)
                h.append(f"<tr><td>frame {i}</td>{tags}</tr>")
            h.append("</table>")
    if failures:
        h.append("<h2>Ordering check failed</h2><ul>" + "".join(f"<li>{html.escape(x)}</li>" for x in failures) + "</ul>")
    h.append("</body></html>")
    write_atomic(os.path.join(out, "report.html"), "\n".join(h))




def independent_table1_lines(c, noise):
    """summary.md's section of Table 1 against the independent second reference of every scored
    frame: each scene's references' own variance, the table, its target misses."""
    sigma2 = {scene: [r["sigma2_x100"] for rows in n["sequences"].values() for r in rows] for scene, n in noise.items()}
    md = ["## Table 1 against an independent reference per frame (--second-references)", "",
          f"Every scored frame traced again with --ref-seed {NOISE_SEED} (<scene>/{NOISE_DIR}/, "
          "scripts/reference_noise.py), independent of the training target: LPIPS against it, MSE×100 against it "
          "less its own variance σ² (an unbiased estimate against the converged image, docs/metrics.md \"Reference "
          "noise\"); the floor is the training reference's round trip scored the same way. σ²×100 of a reference "
          "(mean over the scored frames): " + ", ".join(f"{scene} {sum(v) / len(v):.4f}" for scene, v in sigma2.items()) +
          ". Against the mean of both references and against r₁: <scene>/" + NOISE_DIR + "/reference_noise.md.", ""]
    entries = independent_table1_summary(noise)
    if entries is None:
        return md + ["(no Table 1: it needs the three edit sequences of the paper's scenes)", ""]
    t1, misses = table1(c, entries)
    return md + t1 + ["", misses_line(misses, "Targets against these references:"), ""] + \
        [f"- {x}" for x in misses] + [""]


# ---- the workflow's configuration and jobs ----

# The paper-scale preset (issue 16, docs/results.md "Table 1 at the paper's scale"): the paper's
# 1024² images / 128² latents on cbox-specular, 512² on the two larger scenes; frames 0, 20 and
# 40 of the 60 (frame 0 is the training view, whose reference the fits share; every 20th, not
# 15th, keeps the preset within 150 min on the 2-core Intel Xeon: docs/results.md); 512-spp
# references, since 128 spp left the edit metrics dominated by the references' own noise; the
# paper's 3000 stage-1 iterations; no baseline fit (not in the paper's Table 1); convergence on
# the training view only; the refiner 6000 steps with its learning rate decayed along a half cosine
# (docs/results.md "Refiner study": 8 % lower edited LPIPS than 3000 constant-rate steps, ~3.3 min
# more per scene); emission decay 1e-4 in every fit (docs/fitting.md (17); docs/results.md "Emission
# decay": without it the +Ĩa fit's light walks to the parameter clamp and its 64-spp renders are noisy);
# the refiner without dropout (docs/results.md "No dropout, one view": edited LPIPS 5-9 % lower on
# all three scenes, one target fewer missed).
PAPER = {"scenes": ["cbox-specular", "veach-bidir", "dining-room"],
         "scene_res": {"cbox-specular": 1024, "veach-bidir": 512, "dining-room": 512},
         "frame_step": 20, "ref_spp": 512, "training_ref_spp": 512, "fit_iterations": 3000,
         "refiner_iterations": 6000, "refiner_lr_decay": "cosine", "fits": ["e", "ea", "eac"],
         "spp_list": [1, 4, 16, 64, 256], "conv_views": ["training"], "equal_error_max_spp": 64,
         "emitter_response_decay": 1e-4, "refiner_latent_target": "compensated",
         "refiner_dropout": 0.0, "refiner_emitters": True}


def settings(quick=False, scenes=None, out=None, bin=None, shared=None, image_res=None, frames=None, ref_spp=None,
             fit_iterations=None, refiner_iterations=None, spp=64, chunk=8, paper=False, frame_step=None,
             emission_decay=None, emitter_response_decay=None, param=None, second_references=False,
             refiner_latent_target=None, refiner_dropout=None, refiner_emitters=None, exposures=None):
    """The workflow's config (JSON-able): --quick's small sizes, --paper's preset or the full run's;
    flags given explicitly win over the preset's values."""
    p = PAPER if paper else {}
    return {"quick": quick, "paper": paper, "scenes": scenes or p.get("scenes") or (["cbox-specular"] if quick else list(SCENES)),
            "out": os.path.abspath(out or os.path.join(ROOT, "results")),
            "bin": os.path.abspath(bin or os.path.join(ROOT, "build", "apps", "latentpt")),
            "shared": os.path.abspath(shared or os.environ.get("LATENTPT_SHARED", os.path.join(ROOT, "..", "shared"))),
            "root": ROOT, "image_res": image_res or (128 if quick else 256),
            "scene_res": {} if image_res else p.get("scene_res", {}),
            "fit_iterations": fit_iterations or p.get("fit_iterations") or (300 if quick else 1500),
            "refiner_iterations": refiner_iterations or p.get("refiner_iterations") or (300 if quick else 3000),
            "refiner_lr_decay": p.get("refiner_lr_decay", "none"),
            "refiner_latent_target": refiner_latent_target or p.get("refiner_latent_target", "encoded"),
            # None: the fit's own default (not named, so the commands of earlier runs stay as they were)
            "refiner_dropout": p.get("refiner_dropout") if refiner_dropout is None else refiner_dropout,
            "refiner_emitters": p.get("refiner_emitters", False) if refiner_emitters is None else refiner_emitters,
            "emission_decay": p.get("emission_decay", 0) if emission_decay is None else emission_decay,
            "emitter_response_decay": p.get("emitter_response_decay", 0) if emitter_response_decay is None else emitter_response_decay,
            "param": p.get("param", "code") if param is None else param,
            "exposures": list(p.get("exposures", [])) if exposures is None else list(exposures),
            "frames": frames or (3 if quick else None), "frame_step": frame_step or p.get("frame_step", 1),
            "ref_spp": ref_spp or p.get("ref_spp") or (32 if quick else None),
            # an explicit --ref-spp is every reference's, the training view's too
            "training_ref_spp": None if ref_spp else p.get("training_ref_spp"), "fits": p.get("fits", list(FITS)), "spp": spp,
            "spp_list": [1, 16] if quick else p.get("spp_list", [1, 4, 16, 64, 256, 1024]), "chunk": chunk,
            # --quick: its RGB side reaches the latent floor by 2-4 spp at 128²; 1024 cost a minute of CI
            "equal_error_max_spp": p.get("equal_error_max_spp", 128 if quick else 1024),
            "conv_views": p.get("conv_views", ["training", "novel"]), "second_references": second_references}


def image_res_of(c, scene):
    return c.get("scene_res", {}).get(scene, c["image_res"])


def training_ref_spp_of(c, scene):
    return c.get("training_ref_spp") or ref_spp_of(c, scene)


def fits_of(c):
    return c.get("fits", list(FITS))


def configs_for(fits):
    """The table's columns for these fits: CONFIGS whose fit is among them."""
    return [(k, lab) for k, lab in CONFIGS if k.split("+")[0] in fits]


def configs_of(c):
    return configs_for(fits_of(c))


def scene_file(c, scene):
    return os.path.join(c["shared"], "scenes", SCENES[scene][0])


def ref_spp_of(c, scene):
    return c["ref_spp"] or SCENES[scene][2]


def frames_arg(c, scene, kind):
    """`render --edit --frames A:B:S` of the frames the experiment evaluates."""
    frames = frames_evaluated(c, scene, kind)
    return f"{frames[0]}:{frames[-1]}:{c.get('frame_step', 1)}"


def edit_metrics(binary, threads, fitdir, edits, out, spp, ref_spp, refs, frames, log, who):
    """Renders `frames` (A:B:S) of an edit sequence with a fit against cached references, logged
    (run_logged), and returns the rows of its metrics CSV."""
    run_logged(edit_argv(binary, threads, fitdir, edits, out, spp, ref_spp, refs, frames), log, who)
    first, last, _ = (int(x) for x in frames.split(":"))
    return read_metrics(os.path.join(out, f"metrics_{first}-{last}.csv"))


def frame_count(c, scene, kind):
    if c["frames"]:
        return c["frames"]
    with open(os.path.join(c["root"], "scenes", scene, f"edits-{kind}.json")) as f:
        return json.load(f).get("frames", 60)


def frames_evaluated(c, scene, kind):
    """The frames of a sequence that are rendered and scored: every frame_step-th from 0."""
    return list(range(0, frame_count(c, scene, kind), c.get("frame_step", 1)))


def chunks(c, scene, kind):
    """Frame ranges (first, last) of one sequence's jobs, `chunk` evaluated frames each."""
    f, k = frames_evaluated(c, scene, kind), max(1, c["chunk"])
    return [(f[i], f[min(i + k, len(f)) - 1]) for i in range(0, len(f), k)]


def refiner_setting_args(c, prefix):
    """The config's refiner settings as options of `latentpt fit` (prefix "--refiner-") or `refine`
    ("--"). Each is named only when on, so the commands of constant-rate configs (and configs
    written before the option, which have no key) stay as they were."""
    args = []
    if c.get("refiner_lr_decay", "none") != "none":
        args += [prefix + "lr-decay", c["refiner_lr_decay"]]
    if c.get("refiner_latent_target", "encoded") != "encoded":
        args += [prefix + "latent-target", c["refiner_latent_target"]]
    if c.get("refiner_dropout") is not None:
        args += [prefix + "dropout", repr(float(c["refiner_dropout"]))]
    return args


def fit_argv(c, scene, name, threads, out, iterations=None, final_spp=64, refiner=None, decay=True):
    """`latentpt fit` arguments of one ablation fit into `out` (iterations: the config's;
    refiner: None = as the fit's FITS entry says, False = stage 1 only; decay: pass the config's
    emission decay; the training-reference job's fit is scratch, and without it its command, and
    so its cached job, stay as they were)."""
    terms, extra, refine, lr = FITS[name]
    refine = refine if refiner is None else refiner
    its, res = c["fit_iterations"], image_res_of(c, scene)
    cmd = [c["bin"], "--threads", str(threads), "fit", scene_file(c, scene), "--encode", "--encode-res", f"{res}x{res}",
           "--ref-spp", str(training_ref_spp_of(c, scene)), "--reference-cache", os.path.join(scene, "refs"),
           "--iterations", str(iterations or its), "--spp", "4", "--lr", str(lr),
           "--lr-period", str(its), "--final-spp", str(final_spp), "--terms", terms, "-q", "--out", out] + extra
    # One cosine period to its end, no early stopping: the smoothed loss sits on a plateau while
    # the learning rate is high, and patience 300 stopped cbox-specular's eac fit there (iteration
    # 937 of 3000, loss 0.0277 against ea's 0.0209), so the ablation compared unequal fits.
    cmd += ["--patience", "0"]
    cmd += ["--refiner-iterations", str(c["refiner_iterations"])] if refine else ["--no-refiner"]
    if refine:
        cmd += refiner_setting_args(c, "--refiner-")
    if decay and c.get("emission_decay", 0):
        cmd += ["--emission-decay", repr(float(c["emission_decay"]))]
    if decay and c.get("emitter_response_decay", 0):
        cmd += ["--emitter-response-decay", repr(float(c["emitter_response_decay"]))]
    # the training reference's scratch fit too: it then traces the linear values the exposures'
    # targets scale, once, before the fits that read them
    if c.get("exposures"):
        cmd += ["--exposures", ",".join(repr(float(k)) for k in c["exposures"])]
    # named only when not the default, never over a fit's own (the baseline's classic), and not
    # in the training-reference job's scratch fit (`decay` False), whose command stays as it was
    if decay and c.get("param", "code") != "code" and "--param" not in extra:
        cmd += ["--param", c["param"]]
    for define in SCENES[scene][1]:
        cmd += ["-D", define]
    return cmd


# The emitter refiner (docs/refiner.md "Emitter refiner"): film shifts, a quarter of the width,
# 3000 steps; on the Cornell box as good as a full-width 6000-step one (docs/results.md).
EMITTER_REFINER_ARGS = ["--emitters", "--augment", "shift", "--expansion", "4", "--iterations", "3000",
                        "--patience", "0"]


def emitter_refiner_argv(c, fitdir, threads):
    """`latentpt refine --emitters` beside a fit's refiner, with the config's other refiner settings."""
    return [c["bin"], "--threads", str(threads), "refine", fitdir, "-q"] + EMITTER_REFINER_ARGS + \
        refiner_setting_args(c, "--")


def fit_command(c, scene, name, threads):
    """`latentpt fit` of one ablation fit (and with refiner_emitters its emitter refiner); --resume
    continues a killed one from its checkpoint."""
    d = os.path.join(scene, "fit_" + name)
    # --restart-if-changed: a rerun with changed parameters (Snakemake reruns the job) must not
    # continue the old fit's checkpoint; a killed run of the same command continues it.
    cmd = shlex.join(fit_argv(c, scene, name, threads, d)) + \
        f" $([ -f {shlex.quote(d)}/checkpoint/state.json ] && echo --resume --restart-if-changed)"
    if not (FITS[name][2] and c.get("refiner_emitters")):
        return cmd
    # in a subshell, so that the job's "> log 2>&1" takes both commands' output
    return "( " + cmd + " && " + shlex.join(emitter_refiner_argv(c, d, threads)) + \
        f" $([ -f {shlex.quote(d)}/refiner_emitters_checkpoint.pt ] && echo --resume --restart-if-changed) )"


def training_reference_command(c, scene, threads):
    """A one-iteration fit without refiner whose job is to trace and encode the training view's
    reference into <scene>/refs once (its fit folder is scratch)."""
    return shlex.join(fit_argv(c, scene, "e", threads, os.path.join(scene, "refs", "training_fit"), iterations=1, final_spp=1,
                                decay=False))


def edit_argv(binary, threads, fitdir, edits, out, spp, ref_spp, refs, frames=None, frame_cache=None):
    """`latentpt render <fitdir> --edit --reference` of the frames "A:B:S" (all when None) against
    references cached in `refs`, resuming a killed run; with `frame_cache` the frames that show the
    training view are rendered once for all sequences. Snakemake compares its jobs' commands
    with the recorded ones: keep the order of the arguments."""
    cmd = [binary, "--threads", str(threads), "render", fitdir, "--edit", edits, "--reference", "--ref-spp",
           str(ref_spp), "--reference-cache", refs, "--spp", str(spp), "-q", "--resume", "--out", out]
    return cmd + (["--frames", frames] if frames else []) + (["--frame-cache", frame_cache] if frame_cache else [])


def edit_command(c, scene, fit, edits, out, spp, threads, frames=None):
    """edit_argv of one ablation fit and frames A:B (all when None), as a shell command; the
    scene's sequences and convergence renders share the frames that show the training view."""
    spec = f"{frames[0]}:{frames[1]}:{c.get('frame_step', 1)}" if frames else None
    return shlex.join(edit_argv(c["bin"], threads, os.path.join(scene, "fit_" + fit), edits, out, spp,
                                ref_spp_of(c, scene), os.path.join(scene, "refs"), spec,
                                os.path.join(scene, "frames")))


def second_reference_command(c, scene, kind, threads):
    """--second-references: the eac fit's render of one sequence's scored frames against references
    traced with --ref-seed NOISE_SEED (cached in <scene>/refs beside the first ones, named _seed1)."""
    cmd = edit_argv(c["bin"], threads, os.path.join(scene, "fit_eac"), os.path.join(scene, f"edits-{kind}.json"),
                    os.path.join(scene, NOISE_DIR, kind), c["spp"], ref_spp_of(c, scene), os.path.join(scene, "refs"),
                    frames_arg(c, scene, kind))
    return shlex.join(cmd + ["--ref-seed", str(NOISE_SEED)])


def reference_noise_command(c, scene):
    """scripts/reference_noise.py --ablation on the scene's scored frames and both references."""
    frames = {kind: frames_evaluated(c, scene, kind) for kind in KINDS}
    if any(f != frames[KINDS[0]] for f in frames.values()):
        raise ValueError(f"{scene}: --second-references needs the same frames in every edit sequence, have {frames}")
    return shlex.join([sys.executable, os.path.join(ROOT, "scripts", "reference_noise.py"), "--scene-dir", scene,
                       "--seed-dir", NOISE_DIR, "--seed", str(NOISE_SEED), "--ablation", "--size", str(image_res_of(c, scene)),
                       "--ref-spp", str(ref_spp_of(c, scene)), "--frames", ",".join(map(str, frames[KINDS[0]])),
                       "--bin", c["bin"]] + fits_option(c))


def fits_option(c):
    """reference_noise.py's --fits when the run's fits are not the ablation's three (so that a
    narrowed run scores its own fits' frames, not an older run's beside them; the commands of
    whole runs stay as they were)."""
    fits = [f for f in fits_of(c) if f != "baseline"]
    return [] if fits == ["e", "ea", "eac"] else ["--fits", ",".join(fits)]


def edit_sequence(c, scene, kind):
    """The edit file of a sequence, with the frame count of this config."""
    with open(os.path.join(c["root"], "scenes", scene, f"edits-{kind}.json")) as f:
        e = json.load(f)
    if c["frames"]:
        e["frames"] = c["frames"]
    return e


def view_sequence(c, scene, view):
    """One frame: the training view, or the camera edit's last keyframe held (a novel view)."""
    if view == "training":
        return {"frames": 1}
    with open(os.path.join(c["root"], "scenes", scene, "edits-camera.json")) as f:
        orbit = dict(json.load(f)["camera"]["orbit"])
    for k in ("azimuth", "elevation"):
        if isinstance(orbit.get(k), list):
            orbit[k] = orbit[k][-1]
    return {"frames": 1, "camera": {"orbit": orbit}}


def merge_metrics(parts, out):
    """metrics.csv of a sequence from its chunks' metrics_A-B.csv: one header, rows in order,
    byte for byte what one job over the whole sequence writes."""
    lines = []
    for i, p in enumerate(parts):
        with open(p) as f:
            rows = f.read().splitlines(keepends=True)
        lines += rows if i == 0 else rows[1:]
    write_atomic(out, "".join(lines))


def sequence_table(rows):
    """Per config: mean metrics and per-frame curves of one edit sequence."""
    table = {}
    for key, _ in configs_for(rows):
        src, pre = (rows[key[:-len("+refiner")]], "refined_") if key.endswith("+refiner") else (rows[key], "")
        table[key] = {m: mean(src, pre + m) for m in ("rgb_lpips", "rgb_mse_x100", "latent_dssim", "latent_mse")}
        table[key]["per_frame_lpips"] = [float(r[pre + "rgb_lpips"] or "nan") for r in src]
        table[key]["per_frame_dssim"] = [float(r[pre + "latent_dssim"] or "nan") for r in src]
        table[key]["frames"] = [int(r["frame"]) for r in src]
    return table


def sequence_frames(table):
    """The frames a sequence's table holds (every config of it has the same)."""
    return next(iter(table.values()))["frames"]


def strip_rows(table, columns, scene, kind):
    """report.html's frames of a sequence (first, middle, last): [(frame, [image relative to the
    report, one per column])]."""
    frames = sequence_frames(table)
    return [(i, [f"{scene}/{kind}_{fit}/{png.format(i=i)}" for _, fit, png in columns])
            for i in sorted({frames[0], frames[len(frames) // 2], frames[-1]})]


def strip_columns(fits):
    """report.html's image strip of a sequence for the fits run: (label, fit, frame file)."""
    columns = [("reference", "eac", "frame_{i:04d}_reference.png")]
    if "e" in fits:
        columns.append(("Ĩe", "e", "frame_{i:04d}.png"))
    columns += [("+Ĩa+Ĩc", "eac", "frame_{i:04d}_rendered.png"), ("+refiner", "eac", "frame_{i:04d}.png")]
    if "baseline" in fits:
        columns.append(("baseline + refiner", "baseline", "frame_{i:04d}.png"))
    return columns


def without_timings(d):
    """A results dict without its wall-clock entries ("seconds*"), which differ run to run."""
    if not isinstance(d, dict):
        return d
    return {k: without_timings(v) for k, v in d.items() if not k.startswith("seconds")}


def scene_summary(c, out, scene, failures):
    """Results of one scene from its finished outputs under `out`; ordering failures appended."""
    d = os.path.join(out, scene)
    with open(os.path.join(d, "fit_eac", "metrics.json")) as f:
        train = without_timings(json.load(f))
    s = {"training_view": train, "ref_spp": ref_spp_of(c, scene), "edits": {}, "convergence": {}}
    r_l, f_l = train["rendered"].get("rgb_lpips"), train["refined"].get("rgb_lpips")
    if r_l is None or f_l is None:
        failures.append(f"{scene}: the training view has no LPIPS score (no LPIPS weights?): the orderings are unchecked")
    elif f_l > r_l * 1.0001:
        failures.append(f"{scene}: refiner worse than the rendered latent on the training view (LPIPS {f_l:.4f} > {r_l:.4f})")
    for kind in KINDS:
        table = sequence_table({name: read_metrics(os.path.join(d, f"{kind}_{name}", "metrics.csv")) for name in fits_of(c)})
        s["edits"][kind] = table
        if "e" not in table:  # fits narrowed (--config fits=[...]): nothing to order against
            continue
        base = table["e"]["rgb_lpips"]
        for key in ("ea", "eac"):
            # written so that a NaN (a frame without its LPIPS score) fails rather than passes
            value = table[key]["rgb_lpips"] if key in table else None
            if value is not None and not value <= base * 1.05:
                unscored = " (nan: a frame without its LPIPS score)" if value != value or base != base else ""
                failures.append(f"{scene}/{kind}: {key} LPIPS {value:.4f} worse than e alone {base:.4f}{unscored}")
    for view in c.get("conv_views", ["training", "novel"]):
        s["convergence"][view] = {}
        for spp in c["spp_list"]:
            r = read_metrics(os.path.join(d, f"conv_{view}_{spp}", "metrics.csv"))[0]
            s["convergence"][view][spp] = {k: float(r[k] or "nan") for k in
                                           ("latent_dssim", "rgb_lpips", "refined_latent_dssim", "refined_rgb_lpips")}
    return s


STAGES = {"fit": "fits", "edit": "edits (references + renders)", "conv": "convergence", "equal": "equal-error benchmark",
          "noise": "second references (+ their scores)"}


def benchmark_seconds(path):
    """A job's wall seconds from its Snakemake benchmark file."""
    with open(path) as f:
        return sum(float(r["s"]) for r in csv.DictReader(f, delimiter="\t"))


def job_times(out, scene):
    """Seconds per stage summed over the scene's jobs (Snakemake's benchmark files)."""
    times = {}
    bdir = os.path.join(out, scene, "benchmarks")
    for name in sorted(os.listdir(bdir)) if os.path.isdir(bdir) else []:
        stage = STAGES.get(name.split("_")[0], name.split("_")[0])
        times[stage] = times.get(stage, 0.0) + benchmark_seconds(os.path.join(bdir, name))
    return times


def write_summary(c, out):
    """summary.md, summary.json, timings.json, plots and report.html of every scene of `c`."""
    failures, summary, timings, noise = [], {}, {}, {}
    for scene in c["scenes"]:
        summary[scene] = scene_summary(c, out, scene, failures)
        with open(os.path.join(out, scene, "equal_error.txt")) as f:  # timings: not in summary.json
            timings[scene] = {"stages": job_times(out, scene), "equal_error": f.read()}
        if c.get("second_references"):
            with open(os.path.join(out, scene, NOISE_DIR, "reference_noise.json")) as f:
                noise[scene] = json.load(f)
    return write_outputs(out, c, summary, failures, timings, noise), failures
