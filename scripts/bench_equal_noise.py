#!/usr/bin/env python3
"""Equal-noise benchmark (docs/sampling.md, "Equal noise"): samples per pixel and seconds each
renderer needs to reach one noise level on a scene, measured in one run on one machine:
latentpt with the independent sampler and with Owen-scrambled Sobol (`latentpt bench
--equal-noise`), and Blender Cycles on the same spp ladder (tools/cycles_reference.py; Debian's
`blender`, installed on demand, validation only: without it the Cycles column stays empty and
the report says so).

Noise = emitter-masked relMSE (`latentpt compare`, docs/validation.md (3)) against a converged
reference: Bitterli's Tungsten render for cornell-box, else a high-spp latentpt render made once
and cached. Each renderer renders the ladder 4, 8, ..., 256 spp (each point the mean relMSE of
--seeds renders); the spp and the render time to reach the target are interpolated log-log
between the two ladder points around it. Target: the independent sampler's noise at --target-spp.
Render times are the renderers' own (latentpt's printed render time, Cycles' render time in its
sidecar JSON): process start-up and scene translation are left out on both sides.

    python3 scripts/bench_equal_noise.py                       # cornell-box, 256x256
    python3 scripts/bench_equal_noise.py --scene cbox-specular
    python3 scripts/bench_equal_noise.py --scene cbox-specular --diffuse-mirrors

Outputs <out>/<scene>/report.md and report.json (written atomically); Cycles renders and the
cached reference are kept and reused when rerun with the same settings and code (--force redoes
them); latentpt's ladders are rendered anew each run.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from validate_renderer import blender_env, content_sha1, fingerprint, scene_variant, shared_dir  # noqa: E402

SCENES = {  # name -> (scene file, converged reference under <shared>/scenes or None)
    "cornell-box": ("cornell-box/scene_v3.xml", "cornell-box/TungstenRender.exr"),
    "cbox-specular": ("cbox/cbox_specular.xml", None),
}


def run(cmd, env=None):
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        sys.exit("bench_equal_noise: command failed (exit %d): %s\n%s" % (r.returncode, " ".join(cmd), (r.stdout + r.stderr)[-3000:]))
    return r.stdout + r.stderr


def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def cached(path, settings, force):
    stamp = path + ".json"
    if force or not os.path.exists(path) or not os.path.exists(stamp):
        return None
    with open(stamp) as f:
        old = json.load(f)
    return old if old.get("settings") == settings else None


def render(kind, args, scene, spp, seed, path):
    """Renders unless cached; returns render seconds (the renderer's own count)."""
    tool = os.path.join(ROOT, "tools", "cycles_reference.py") if kind == "cycles" else args.bin
    settings = {"kind": kind, "scene": scene, "scene_sha1": content_sha1(scene), "res": args.res, "spp": spp, "seed": seed, "code": fingerprint(tool)}
    if kind == "cycles":
        settings["pattern"] = args.cycles_pattern
    old = cached(path, settings, args.force)
    if old:
        return old["seconds"]
    res = "%dx%d" % (args.res, args.res)
    if kind == "cycles":
        run([args.blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
             os.path.join(ROOT, "tools", "cycles_reference.py"), "--", scene, "--res", res, "--spp", str(spp),
             "--seed", str(seed), "--threads", str(args.threads), "--pattern", args.cycles_pattern, "--out", path],
            env=blender_env(args.blender))
        with open(path + ".json") as f:
            side = json.load(f)
        seconds = float(side["render_time_s"])  # bpy.ops.render.render: sync, BVH and sampling
        os.replace(path + ".json", path + ".cycles.json")
    else:
        out = run([args.bin, "--threads", str(args.threads), "--sampler", kind, "render", scene, "--res", res, "--spp", str(spp),
                   "--seed", str(seed), "--out", path])  # not -q: the closing line carries the render time
        m = re.search(r"rays, ([0-9.eE+-]+) s\)", out)
        if not m:
            sys.exit("bench_equal_noise: no render time in latentpt's output:\n" + out)
        seconds = float(m.group(1))
    write_atomic(path + ".json", json.dumps({"settings": settings, "seconds": seconds}) + "\n")
    return seconds


def rel_mse(args, exr, ref, scene):
    out_dir = exr + ".cmp"
    run([args.bin, "compare", "--test", exr, "--ref", ref, "--scene", scene, "-o", out_dir])
    with open(os.path.join(out_dir, "comparison.json")) as f:
        return json.load(f)["rel_mse"]


def to_target(ladder, target):
    """(spp, seconds) where the log-log interpolated noise reaches target; None if never."""
    for (s0, t0, e0), (s1, t1, e1) in zip(ladder, ladder[1:]):
        if e0 >= target >= e1 and e0 > 0 and e1 > 0 and e0 != e1:
            f = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e1))
            spp = math.exp(math.log(s0) + f * (math.log(s1) - math.log(s0)))
            return spp, t0 + (t1 - t0) * (spp - s0) / (s1 - s0)
    if ladder and ladder[0][2] <= target:
        s0, t0, _ = ladder[0]
        return s0, t0
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="cornell-box", choices=sorted(SCENES))
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--target-spp", type=int, default=64, help="target noise = the independent sampler's at this spp")
    ap.add_argument("--seeds", type=int, default=2, help="renders per ladder point (their relMSE is averaged)")
    ap.add_argument("--ref-spp", type=int, default=4096, help="spp of the cached reference where no converged one ships")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench-out", "equal-noise"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "latentpt"))
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--no-cycles", action="store_true", help="leave the Cycles column empty")
    ap.add_argument("--cycles-pattern", choices=("pmj", "sobol"), default="pmj",
                    help="Cycles' sampling pattern (tools/cycles_reference.py --pattern); default pmj, Blender's own "
                         "default, as the documented runs used")
    ap.add_argument("--diffuse-mirrors", action="store_true",
                    help="smooth conductors made diffuse (a rewritten copy of the scene, its own reference): "
                         "how much of the noise is light that mirrors reflect onto diffuse surfaces")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args()

    scene_rel, ref_rel = SCENES[args.scene]
    scene = os.path.join(shared_dir(), "scenes", scene_rel)
    if not os.path.exists(scene):
        sys.exit("bench_equal_noise: %s not found (set LATENTPT_SHARED)" % scene)
    name = args.scene + ("-diffuse-mirrors" if args.diffuse_mirrors else "")
    folder = os.path.join(args.out, name)
    os.makedirs(folder, exist_ok=True)
    if args.diffuse_mirrors:
        scene, _ = scene_variant(scene, folder, "scene", diffuse_mirrors=True)
        ref_rel = None  # a shipped reference shows the scene with its mirrors
    if ref_rel:
        ref = os.path.join(shared_dir(), "scenes", ref_rel)
        ref_note = "Tungsten reference (%s), box-averaged to %d²" % (ref_rel, args.res)
    else:
        ref = os.path.join(folder, "reference.exr")
        render("sobol", argparse.Namespace(**{**vars(args), "force": False}), scene, args.ref_spp, 1000, ref)
        ref_note = "latentpt, Sobol, %d spp (its own noise is a floor under every relMSE)" % args.ref_spp
    ours_json = os.path.join(folder, "latentpt.json")
    run([args.bin, "--threads", str(args.threads), "bench", "--equal-noise", "--scene", scene, "--reference", ref, "--res", str(args.res),
         "--target-spp", str(args.target_spp), "--seeds", str(args.seeds), "--json", ours_json])
    with open(ours_json) as f:
        ours = json.load(f)
    ladders = {k: [tuple(p) for p in v] for k, v in ours["ladders"].items()}
    target = ours["target"]
    ladder_spp = [p[0] for p in ladders["independent"]]
    for kind in ("independent", "sobol"):
        for spp, sec, err in ladders[kind]:
            print("equal-noise: %-11s %4d spp  %7.2f s  relMSE %.6f" % (kind, spp, sec, err), flush=True)
    have_blender = not args.no_cycles and shutil.which(args.blender) is not None
    for kind in ["cycles"] if have_blender else []:
        pts = []
        for spp in ladder_spp:
            secs, errs = [], []
            for seed in range(1, args.seeds + 1):
                exr = os.path.join(folder, "%s_%s_%d_s%d.exr" % (kind, args.cycles_pattern, spp, seed))
                secs.append(render(kind, args, scene, spp, seed, exr))
                errs.append(rel_mse(args, exr, ref, scene))
            pts.append((spp, sum(secs) / len(secs), sum(errs) / len(errs)))
            print("equal-noise: %-11s %4d spp  %7.2f s  relMSE %.6f" % (kind, spp, pts[-1][1], pts[-1][2]), flush=True)
        ladders[kind] = pts
    reach = {k: to_target(v, target) for k, v in ladders.items()}

    def cell(v, fmt):
        return fmt % v if v is not None else "–"

    lines = ["# Equal noise: %s, %d², target relMSE %.6f (independent at %d spp)" % (name, args.res, target, args.target_spp), "",
             "Reference: %s. %d thread(s); render times only; each ladder point the mean of %d seeds." % (ref_note, args.threads, args.seeds), "",
             "| renderer | spp to target | seconds to target | spp ratio (independent / this) | speed-up vs independent | speed-up vs Cycles |",
             "|---|---|---|---|---|---|"]
    ind, cyc = reach["independent"], reach.get("cycles")
    for kind in ["independent", "sobol", "cycles"]:
        r = reach.get(kind)
        if kind == "cycles" and not have_blender:
            why = "not run (--no-cycles)" if args.no_cycles else "no Blender: `apt-get install blender`"
            lines.append("| Cycles | – (%s) | – | – | – | – |" % why)
            continue
        label = {"independent": "latentpt independent", "sobol": "latentpt sobol",
                 "cycles": "Cycles (CPU, %s pattern)" % args.cycles_pattern}[kind]
        lines.append("| %s | %s | %s | %s | %s | %s |" % (
            label, cell(r and r[0], "%.1f"), cell(r and r[1], "%.2f"), cell(r and ind and ind[0] / r[0], "%.2f×"),
            cell(r and ind and ind[1] / r[1], "%.2f×"), cell(r and cyc and cyc[1] / r[1], "%.2f×")))
    lines += ["", "Ladder (spp, seconds, relMSE):", ""]
    for kind, pts in ladders.items():
        lines.append("- %s: %s" % (kind, ", ".join("%d: %.2f s, %.6f" % p for p in pts)))
    text = "\n".join(lines) + "\n"
    write_atomic(os.path.join(folder, "report.md"), text)
    write_atomic(os.path.join(folder, "report.json"), json.dumps(
        {"scene": name, "res": args.res, "target": target, "target_spp": args.target_spp, "reference": ref_note,
         "threads": args.threads, "cycles_pattern": args.cycles_pattern if have_blender else None, "ladders": ladders,
         "reach": reach}, indent=1) + "\n")
    print(text)


if __name__ == "__main__":
    main()
