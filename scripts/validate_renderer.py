#!/usr/bin/env python3
"""latentpt's RGB path tracer against an independent renderer (Blender Cycles) on the paper's
scenes: docs/validation.md. Python standard library only; drives the latentpt binary, Blender
(Debian's `blender`, installed on demand: `apt-get install blender`; validation only) through
tools/cycles_reference.py, and `latentpt compare`.

For each scene, both renderers render it twice with independent seeds at half the sample count
each (the two halves give each side's noise), then `latentpt compare` reports channel-mean
ratios, 32x32 block ratios against their noise, emitter-masked relMSE and pictures:

    <out>/<scene>/ours_{1,2}.exr, cycles_{1,2}.exr (+ .json: Cycles' settings and approximations)
    <out>/<scene>/compare/    comparison.txt/.json, side_by_side.png, ratio_map.png
    <out>/summary.md, summary.json

With --split, ours also renders the scene as the Cycles translation approximates it (the
validation-only key cycles_approximation on every plastic, roughplastic and roughconductor,
docs/bsdfs.md (47)-(49)), which splits the difference in two:

    <out>/<scene>/translation/     ours / ours approximated: what the translation changes
    <out>/<scene>/compare_approx/  ours approximated / Cycles: what is left

Finished renders are reused when rerun with the same settings and the same latentpt binary /
translation script (resumable; a rebuilt latentpt renders again); --force redoes them.
Without Blender the Cycles side is skipped and the summary says so.
"""
import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# name -> scene file under <shared>/scenes
SCENES = {
    "cornell-box": "cornell-box/scene_v3.xml",
    "cbox-specular": "cbox/cbox_specular.xml",
    "veach-bidir": "veach-bidir/scene_v3.xml",
    "dining-room": "dining-room/scene_diffuse.xml",
    "classroom": "classroom/scene_constant.xml",
}


def shared_dir():
    return os.environ.get("LATENTPT_SHARED", os.path.join(ROOT, "..", "shared"))


def run(cmd, log, env=None):
    """Runs cmd, appends its output to log, returns seconds; raises with the log's tail on failure."""
    start = time.time()
    with open(log, "a") as f:
        f.write("$ " + " ".join(cmd) + "\n")
        f.flush()
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
    if r.returncode != 0:
        with open(log) as f:
            tail = f.read()[-3000:]
        raise RuntimeError("command failed (exit %d): %s\n%s" % (r.returncode, " ".join(cmd), tail))
    return time.time() - start


def blender_env(blender):
    """Environment for Blender: its embedded Python takes its prefix from the first python3 on PATH, so
    Blender's own folder goes first (a pyenv or virtualenv python3 would hide the system numpy)."""
    env = dict(os.environ)
    exe = shutil.which(blender)
    if exe:
        env["PATH"] = os.path.dirname(os.path.realpath(exe)) + os.pathsep + env.get("PATH", "")
    for k in ("PYTHONHOME", "PYTHONPATH"):
        env.pop(k, None)
    return env


def content_sha1(path):
    """SHA-1 of a file as it is now (a scene file: the rewritten copies keep their paths across
    flags)."""
    h = hashlib.sha1()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


_FINGERPRINTS = {}


def fingerprint(path):
    """content_sha1 of the code that renders (the latentpt binary, the translation script), once per
    run: a render made by other code is not a finished render of this run."""
    if path not in _FINGERPRINTS:
        _FINGERPRINTS[path] = content_sha1(path)
    return _FINGERPRINTS[path]


def render_once(kind, args, scene_path, out_exr, seed, extra, log):
    """Renders unless out_exr exists with the same settings and code (kept in out_exr + '.settings')."""
    tool = args.bin if kind == "ours" else os.path.join(ROOT, "tools", "cycles_reference.py")
    settings = {"kind": kind, "scene": scene_path, "scene_sha1": content_sha1(scene_path), "res": args.res,
                "spp": args.spp // 2, "seed": seed, "extra": extra, "code": fingerprint(tool)}
    if kind == "cycles":
        settings["pattern"] = args.cycles_pattern
    stamp = out_exr + ".settings"
    if not args.force and os.path.exists(out_exr) and os.path.exists(stamp):
        with open(stamp) as f:
            old = json.load(f)
        if {k: v for k, v in old.items() if k != "seconds"} == settings:
            return old.get("seconds", 0.0), True
    res = "%dx%d" % (args.res, args.res)
    if kind == "ours":
        cmd = [args.bin, "--threads", str(args.threads), "render", scene_path, "--res", res, "--spp", str(args.spp // 2),
               "--seed", str(seed), "-q", "--out", out_exr] + extra
    else:
        cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
               os.path.join(ROOT, "tools", "cycles_reference.py"), "--", scene_path, "--res", res, "--spp",
               str(args.spp // 2), "--seed", str(seed), "--threads", str(args.threads), "--pattern", args.cycles_pattern,
               "--out", out_exr] + extra
    seconds = run(cmd, log, blender_env(args.blender) if kind == "cycles" else None)
    settings["seconds"] = seconds
    tmp = stamp + ".tmp"
    with open(tmp, "w") as f:
        json.dump(settings, f)
    os.replace(tmp, stamp)
    return seconds, False


APPROXIMATED_BSDFS = ("plastic", "roughplastic", "roughconductor")
COMMENT = re.compile(r"<!--.*?-->", re.S)


def outside_comments(text, pattern, replace):
    """pattern.sub(replace) on the parts of an XML text that are not <!-- comments --> (the paper's
    scenes keep whole alternatives commented out), and the number of replacements."""
    parts, count, last = [], 0, 0
    for m in list(COMMENT.finditer(text)) + [None]:
        chunk = text[last:m.start() if m else len(text)]
        chunk, n = pattern.subn(replace, chunk)
        parts.append(chunk)
        count += n
        if m:
            parts.append(m.group(0))
            last = m.end()
    return "".join(parts), count


def with_approximations(text):
    """The scene XML with cycles_approximation on every plastic, roughplastic and roughconductor, and
    how many BSDFs that changed."""
    flag = '<boolean name="cycles_approximation" value="true"/>'
    pattern = re.compile(r'<bsdf\b([^>]*\btype\s*=\s*"(?:%s)"[^>]*?)(/?)>' % "|".join(APPROXIMATED_BSDFS))
    return outside_comments(text, pattern,
                            lambda m: "<bsdf%s>%s%s" % (m.group(1), flag, "</bsdf>" if m.group(2) else ""))


def with_face_normals(text):
    """The scene XML with face_normals true on every obj and ply shape (flat shading: shading normal =
    geometric normal in both renderers), and how many shapes that changed."""
    pattern = re.compile(r'(<shape\b[^>]*\btype\s*=\s*"(?:obj|ply)"[^>]*?(?<!/)>)(.*?)(</shape>)', re.S)
    existing = re.compile(r'<boolean\b[^>]*\bname\s*=\s*"face_normals"[^>]*>(\s*</boolean>)?')
    flag = '<boolean name="face_normals" value="true"/>'

    def flatten(m):
        body = existing.sub("", m.group(2))
        return m.group(1) + flag + body + m.group(3)

    return outside_comments(text, pattern, flatten)


def with_box_filter(text):
    """The scene XML with every <rfilter> a box of Mitsuba's default radius (Cycles has one exactly;
    Mitsuba's tent it only approximates by a Gaussian of the same variance), and how many filters
    that changed."""
    pattern = re.compile(r'<rfilter\b[^>]*?(/>|>.*?</rfilter>)', re.S)
    return outside_comments(text, pattern, lambda m: '<rfilter type="box"/>')


def with_diffuse_mirrors(text):
    """The scene XML with every smooth conductor (a delta lobe: the light it reflects onto diffuse
    surfaces is found only by BSDF sampling, never by NEE) replaced by a diffuse BSDF of reflectance
    0.8 under the same id, and how many BSDFs that changed (docs/sampling.md, "Equal noise")."""
    pattern = re.compile(r'<bsdf\b([^>]*?)\btype\s*=\s*"conductor"([^>]*?)(/>|>.*?</bsdf>)', re.S)
    return outside_comments(text, pattern, lambda m: '<bsdf%stype="diffuse"%s><rgb name="reflectance" value="0.8"/></bsdf>'
                            % (m.group(1), m.group(2)))


def scene_variant(scene_path, folder, name, approximate=False, flat=False, box=False, diffuse_mirrors=False):
    """A rewritten copy of the scene XML (with_approximations, with_face_normals, with_box_filter,
    with_diffuse_mirrors) in <folder>/<name>/ beside links to everything else of the scene's folder
    (meshes and textures are named relative to the XML). Returns its path and how many BSDFs, meshes
    and filters it changed."""
    with open(scene_path) as f:
        text = f.read()
    changed = {"bsdfs": 0, "meshes": 0, "filters": 0, "mirrors": 0}
    for wanted, rewrite, kind, what in (
            (approximate, with_approximations, "bsdfs", "plastic, roughplastic or roughconductor"),
            (flat, with_face_normals, "meshes", "obj or ply mesh"), (box, with_box_filter, "filters", "rfilter"),
            (diffuse_mirrors, with_diffuse_mirrors, "mirrors", "smooth conductor")):
        if wanted:
            text, changed[kind] = rewrite(text)
            if changed[kind] == 0:  # a rewrite that found nothing would compare the scene with itself
                sys.exit("%s: no %s to rewrite (for the copy '%s')" % (scene_path, what, name))
    out_dir = os.path.join(folder, name)
    os.makedirs(out_dir, exist_ok=True)
    src_dir = os.path.dirname(os.path.abspath(scene_path))
    for entry in os.listdir(src_dir):
        link = os.path.join(out_dir, entry)
        if entry != os.path.basename(scene_path) and not os.path.lexists(link):
            os.symlink(os.path.join(src_dir, entry), link)
    out = os.path.join(out_dir, os.path.basename(scene_path))
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, out)
    return out, changed


def compare(args, log, test, ref, scene_path, out_dir, extra):
    """`latentpt compare` of two render pairs; prints its text and returns the summary fields."""
    cmd = [args.bin, "compare", "--test"] + test + ["--ref"] + ref + ["--scene", scene_path, "-o", out_dir] + extra
    run(cmd, log)
    with open(os.path.join(out_dir, "comparison.json")) as f:
        c = json.load(f)
    with open(os.path.join(out_dir, "comparison.txt")) as f:
        print(f.read(), flush=True)
    blocks = [b for b in c["blocks"] if b["pixels"] > 0]
    return {
        "mean_ratio": c["mean_ratio"], "mean_ratio_sigma": c["mean_ratio_sigma"], "rel_mse": c["rel_mse"],
        "blocks": len(blocks), "blocks_flagged": c["blocks_flagged"],
        "blocks_brighter": sum(1 for b in blocks if b["ratio"] > 1.0),
        "max_abs_z": max(abs(b["z"]) for b in blocks) if blocks else 0.0,
    }


def approximations(cycles_exr):
    try:
        with open(cycles_exr + ".json") as f:
            return json.load(f).get("approximations", [])
    except (OSError, ValueError):
        return []


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated, from: " + ", ".join(SCENES))
    ap.add_argument("--res", type=int, default=256, help="square image resolution")
    ap.add_argument("--spp", type=int, default=1024, help="samples per pixel per renderer (two renders of spp/2)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--out", default=os.path.join(ROOT, "validation-out"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "latentpt"))
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--force", action="store_true", help="re-render even where finished renders exist")
    ap.add_argument("--cycles-pattern", choices=("sobol", "pmj"), default="sobol",
                    help="Cycles' sampling pattern (tools/cycles_reference.py --pattern): sobol, or pmj (Blender's "
                         "default, biased at low sample counts on tessellated sphere lights; the runs before "
                         "2026-11-26 evening used it)")
    ap.add_argument("-D", dest="defines", action="append", default=[], help="scene override for both renderers, e.g. max_depth=6")
    ap.add_argument("--flat-shading", action="store_true",
                    help="both renderers render every obj/ply mesh with face normals (a rewritten copy of the scene): "
                         "separates how the renderers treat smooth shading normals from the rest")
    ap.add_argument("--box-filter", action="store_true",
                    help="both renderers use a box pixel filter (a rewritten copy of the scene): Cycles has no tent")
    ap.add_argument("--split", action="store_true",
                    help="also render ours as the Cycles translation approximates plastic, roughplastic and roughconductor "
                         "(seeds 3 and 4) and compare it with ours and with Cycles (docs/validation.md)")
    args = ap.parse_args()

    have_blender = shutil.which(args.blender) is not None
    if not have_blender:
        print("validate: no Blender (%s) found: the Cycles side is skipped (install: apt-get install blender)" % args.blender)
    extra = []
    for d in args.defines:
        extra += ["-D", d]
    os.makedirs(args.out, exist_ok=True)
    summary = []
    for name in [s for s in args.scenes.split(",") if s]:
        if name not in SCENES:
            sys.exit("validate: unknown scene '%s' (known: %s)" % (name, ", ".join(SCENES)))
        original = os.path.join(shared_dir(), "scenes", SCENES[name])
        if not os.path.exists(original):
            sys.exit("validate: %s not found (set LATENTPT_SHARED)" % original)
        folder = os.path.join(args.out, name)
        os.makedirs(folder, exist_ok=True)
        rewrites = {"flat": args.flat_shading, "box": args.box_filter}
        scene_path = scene_variant(original, folder, "rewritten", **rewrites)[0] if any(rewrites.values()) else original
        log = os.path.join(folder, "log.txt")
        entry = {"scene": name, "file": SCENES[name], "res": args.res, "spp": args.spp, "defines": args.defines,
                 "flat_shading": args.flat_shading, "box_filter": args.box_filter}

        def render_pair(kind, label=None, path=scene_path, seeds=(1, 2)):
            """Both seeds of one renderer; returns their files and seconds."""
            total, files = 0.0, []
            for seed in seeds:
                files.append(os.path.join(folder, "%s_%d.exr" % (label or kind, seed)))
                s, reused = render_once(kind, args, path, files[-1], seed, extra, log)
                total += s
                print("validate: %s %s seed %d: %s" % (name, label or kind, seed, "reused" if reused else "%.1f s" % s),
                      flush=True)
            return files, total

        ours, entry["seconds_ours"] = render_pair("ours")
        if args.split:
            approx_path, changed = scene_variant(original, folder, "approximated", approximate=True, **rewrites)
            entry["approximated_bsdfs"] = changed["bsdfs"]
            approx, entry["seconds_ours_approximated"] = render_pair("ours", "ours_approximated", approx_path, (3, 4))
            entry["translation"] = compare(args, log, ours, approx, scene_path, os.path.join(folder, "translation"), extra)
        if have_blender:
            cycles, entry["seconds_cycles"] = render_pair("cycles")
            entry["approximations"] = approximations(cycles[0])
            entry.update(compare(args, log, ours, cycles, scene_path, os.path.join(folder, "compare"), extra))
            if args.split:
                entry["approximated"] = compare(args, log, approx, cycles, scene_path,
                                                os.path.join(folder, "compare_approx"), extra)
        summary.append(entry)
        write_summary(args.out, summary, have_blender)
    print("validate: wrote %s" % os.path.join(args.out, "summary.md"))


def write_summary(out, summary, have_blender):
    lines = ["| scene | ours / Cycles mean R | G | B | relMSE (emitters masked) | 32² blocks beyond 3σ | max abs(z) | "
             "blocks brighter | time ours / Cycles |", "|---|---|---|---|---|---|---|---|---|"]
    def row(label, c, times):
        r, s = c["mean_ratio"], c["mean_ratio_sigma"]
        return "| %s | %.4f ± %.4f | %.4f ± %.4f | %.4f ± %.4f | %.5f | %d of %d | %.1f | %d | %s |" % (
            label, r[0], s[0], r[1], s[1], r[2], s[2], c["rel_mse"], c["blocks_flagged"], c["blocks"], c["max_abs_z"],
            c["blocks_brighter"], times)

    for e in summary:
        if "mean_ratio" in e:
            lines.append(row(e["scene"], e, "%.0f s / %.0f s" % (e["seconds_ours"], e["seconds_cycles"])))
        else:
            lines.append("| %s | – | – | – | – | – | – | – | %.0f s / (no Blender) |" % (e["scene"], e["seconds_ours"]))
        if "translation" in e:
            lines.append(row("%s: ours / ours approximated (%d BSDFs)" % (e["scene"], e["approximated_bsdfs"]),
                             e["translation"], "%.0f s approximated" % e["seconds_ours_approximated"]))
        if "approximated" in e:
            lines.append(row("%s: ours approximated / Cycles" % e["scene"], e["approximated"], ""))
    text = "\n".join(lines) + "\n"
    if any(e.get("flat_shading") for e in summary):
        text += "\nFlat shading (--flat-shading): both renderers rendered every obj/ply mesh with face normals.\n"
    if any(e.get("box_filter") for e in summary):
        text += "\nBox filter (--box-filter): both renderers used a box pixel filter.\n"
    if not have_blender:
        text += "\nNo Blender on this machine: only our renders were made.\n"
    for e in summary:
        if e.get("approximations"):
            text += "\n%s, Cycles approximations:\n" % e["scene"] + "".join("- %s\n" % a for a in e["approximations"])
    for name, content in (("summary.md", text), ("summary.json", json.dumps(summary, indent=1) + "\n")):
        tmp = os.path.join(out, name + ".tmp")
        with open(tmp, "w") as f:
            f.write(content)
        os.replace(tmp, os.path.join(out, name))


if __name__ == "__main__":
    main()
