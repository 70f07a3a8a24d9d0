#!/usr/bin/env python3
"""Outputs of render, fit (both stages) and edit rendering, compared bit for bit with the ones the
code wrote before a refactor (tests/golden/golden.json).

A restructuring must not change a single output bit: this runs a fixed set of small commands on the
bundled scenes (and ../shared's when present), hashes every image's pixels (oiiotool --hash, so file
metadata does not count) and every JSON / CSV with its timings and absolute paths removed, and
compares the hashes with the stored ones. `--update` stores the current hashes instead: run it only
on the commit whose outputs define the reference, and say so in that commit.

Floating-point results depend on the CPU's instruction set (Embree and libtorch pick their kernels at
run time), so hashes hold for the kind of machine that wrote them. The manifest keeps one set per
kind, named by its CPU model and the vector extensions the kernels choose between (the model string
alone is not enough: two machines that both call themselves "AMD EPYC" wrote different plain
renders). A machine compares its outputs with its own kind's set; a kind with no set reports a skip
(exit 77), not a failure.

    --update        the outputs changed on purpose: this machine's hashes become the only set (the
                    other kinds' no longer describe the outputs; say so in the commit)
    --add-machine   the outputs did not change since the stored sets were written: this machine's
                    hashes join them (refused where its kind's own set holds other hashes)
"""
import argparse
import csv
import hashlib
import io
import json
import os
import platform
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
MANIFEST = os.path.join(HERE, "golden.json")
IMAGE_EXT = (".exr", ".png")
VOLATILE_KEYS = ("seconds", "seconds_per_iteration", "scene", "vae_dir", "lpips_dir", "target", "fitdir",
                 "reference", "vae_encoder", "vae_decoder", "vae_config", "out")


def cpuinfo_field(name):
    """The first /proc/cpuinfo line's value for `name` ("model name", "flags"), or None."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith(name):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def cpu_model():
    return cpuinfo_field("model name") or platform.processor() or "unknown"


# The extensions Embree's and libtorch's run-time dispatch choose kernels by.
DISPATCH_FLAGS = ("sse4_1", "sse4_2", "avx", "avx2", "fma", "f16c", "avx512f", "avx512dq", "avx512cd", "avx512bw",
                  "avx512vl", "avx512_vnni", "avx512_bf16", "amx_tile")


def cpu_isa():
    """The DISPATCH_FLAGS this CPU has, space-separated ("unknown" where /proc/cpuinfo is absent)."""
    flags = cpuinfo_field("flags")
    if flags is None:
        return "unknown"
    have = set(flags.split())
    return " ".join(flag for flag in DISPATCH_FLAGS if flag in have)


def this_machine():
    return cpu_model(), cpu_isa()


def stored_sets():
    """The manifest's hash sets, one per machine kind (a manifest from before 2026-12-08 held one);
    [] without a manifest. Exits naming the file when it is malformed."""
    if not os.path.exists(MANIFEST):
        return []
    try:
        with open(MANIFEST) as f:
            doc = json.load(f)
        sets = doc["machines"] if "machines" in doc else [doc]
        for m in sets:
            if not (isinstance(m["cpu"], str) and isinstance(m["isa"], str) and isinstance(m["runs"], dict)):
                raise ValueError("a set without cpu, isa and runs")
        return sets
    except (ValueError, KeyError, TypeError) as e:
        sys.exit(f"{MANIFEST}: malformed ({e}); golden.py --update writes it again")


def write_manifest(sets):
    tmp_path = MANIFEST + ".tmp"
    with open(tmp_path, "w") as f:
        json.dump({"machines": sets}, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp_path, MANIFEST)


def source_commit(src):
    """The commit the outputs were made from, "-dirty" when the tree had changes beyond it (as when
    --update runs before the commit that changes the outputs: that commit is the next one)."""
    r = subprocess.run(["git", "-C", src, "describe", "--always", "--dirty", "--abbrev=7", "--exclude=*"],
                       capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else "unknown"


def commands(b, src, shared, out, skipped):
    """(name, argv, outputs folder or file prefix): every run is tiny (the whole set takes ~15 s).
    The names of runs left out for want of ../shared data go to `skipped`."""
    box = os.path.join(src, "scenes/cornell-box/scene.json")
    edits = os.path.join(src, "scenes/cornell-box/edits-demo.json")
    small_refiner = ["--refiner-iterations", "4", "--refiner-expansion", "1"]
    runs = [
        ("render_box", [b, "render", box, "--spp", "4", "--res", "32x32", "--aov", "--aov-res", "8x8",
                        "--out", f"{out}/render_box/r.exr"]),
        ("render_box_independent", [b, "--sampler", "independent", "render", box, "--spp", "3", "--res", "24x16",
                                    "--strategy", "nee", "--out", f"{out}/render_box_independent/r.exr"]),
        ("fit_box", [b, "fit", box, "--synthetic-res", "8x8", "--iterations", "20", "--spp", "2", "--final-spp", "4",
                     "-D", "integrator.max_depth=3", *small_refiner, "--out", f"{out}/fit_box"]),
        ("fit_box_replay", [b, "fit", box, "--synthetic-res", "8x8", "--iterations", "12", "--spp", "2",
                            "--final-spp", "4", "--reuse-paths", "0", "--param", "paper", "--gate", "visible",
                            "--no-refiner", "--out", f"{out}/fit_box_replay"]),
        ("edit_box", [b, "render", f"{out}/fit_box", "--edit", edits, "--out", f"{out}/edit_box"]),
    ]
    xml_scenes = [("cbox_specular", "scenes/cbox/cbox_specular.xml", "32x32", "4"),
                  ("veach_bidir", "scenes/veach-bidir/scene_v3.xml", "32x24", "2"),
                  ("dining_room", "scenes/dining-room/scene_diffuse.xml", "32x24", "2"),
                  ("classroom", "scenes/classroom/scene_constant.xml", "32x24", "2")]
    for name, rel, res, spp in xml_scenes:
        path = os.path.join(shared, rel)
        if not os.path.exists(path):
            skipped.append(f"render_{name}")
        else:
            runs.append((f"render_{name}", [b, "render", path, "--spp", spp, "--res", res,
                                            "--out", f"{out}/render_{name}/r.exr"]))
    cbox = os.path.join(shared, "scenes/cbox/cbox_specular.xml")
    if not (os.path.exists(cbox) and os.path.isdir(os.path.join(shared, "models/taesd3"))):
        skipped.append("fit_cbox_encoded")
    else:
        runs.append(("fit_cbox_encoded", [b, "fit", cbox, "--encode", "--encode-res", "64x64", "--ref-spp", "8",
                                          "--iterations", "10", "--spp", "2", "--final-spp", "4", *small_refiner,
                                          "--out", f"{out}/fit_cbox_encoded"]))
    return runs


def image_hash(path):
    r = subprocess.run(["oiiotool", "--hash", "--info", path], capture_output=True, text=True, check=True)
    for line in r.stdout.splitlines():
        if "SHA-1:" in line:
            return line.split("SHA-1:", 1)[1].strip()
    raise RuntimeError(f"oiiotool printed no SHA-1 for {path}")


# Fields added to metrics.json or fit.json after the stored hashes, dropped when they hold the value that means
# "as before": an output that gained a record of a default setting still matches its old hash.
ADDED_DEFAULTS = {"noise_views": 1, "lr_decay": "none", "inference_window": 0, "augment": "none", "emission_decay": 0,
                  "emitter_response_decay": 0, "inference_stride": 0, "latent_target": "encoded", "exposures": []}


def scrub(value):
    if isinstance(value, dict):
        return {k: scrub(v) for k, v in value.items()
                if k not in VOLATILE_KEYS and not (k in ADDED_DEFAULTS and v == ADDED_DEFAULTS[k])}
    if isinstance(value, list):
        return [scrub(v) for v in value]
    return value


def text_hash(path):
    with open(path, newline="") as f:
        text = f.read()
    if path.endswith(".json"):
        text = json.dumps(scrub(json.loads(text)), sort_keys=True)
    elif path.endswith(".csv"):
        rows = list(csv.reader(io.StringIO(text)))
        keep = [i for i, h in enumerate(rows[0]) if h != "seconds"] if rows else []
        text = "\n".join(",".join(r[i] for i in keep) for r in rows)
    return hashlib.sha256(text.encode()).hexdigest()


def hash_outputs(folder):
    hashes = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if d != "checkpoint"]  # resume state, covered by the CLI test
        for name in sorted(files):
            path = os.path.join(root, name)
            rel = os.path.relpath(path, folder)
            if name.endswith(IMAGE_EXT):
                hashes[rel] = image_hash(path)
            elif name.endswith((".json", ".csv")):
                hashes[rel] = text_hash(path)
    return hashes


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="the latentpt binary")
    ap.add_argument("--src", default=os.path.dirname(os.path.dirname(HERE)), help="source tree")
    ap.add_argument("--shared", default=None, help="shared data (default: LATENTPT_SHARED or ../shared)")
    ap.add_argument("--out", default=None, help="keep the outputs here (default: a temporary folder)")
    what = ap.add_mutually_exclusive_group()
    what.add_argument("--update", action="store_true",
                      help="the outputs changed on purpose: store this machine's hashes as the only set")
    what.add_argument("--add-machine", action="store_true",
                      help="the outputs are unchanged: add this machine's hashes beside the stored sets")
    args = ap.parse_args()
    shared = args.shared or os.environ.get("LATENTPT_SHARED") or os.path.join(args.src, "..", "shared")

    sets = stored_sets()  # before the runs: a missing or malformed manifest fails at once
    if not sets and not args.update:
        print(f"{MANIFEST}: missing or empty; golden.py --update stores the hashes", file=sys.stderr)
        return 1
    cpu, isa = this_machine()
    mine = [m for m in sets if (m["cpu"], m["isa"]) == (cpu, isa)]
    skipped = []
    with tempfile.TemporaryDirectory(prefix="latentpt-golden-") as tmp:
        out = args.out or tmp
        current = {}
        for name, argv in commands(args.bin, args.src, shared, out, skipped):
            r = subprocess.run([*argv, "-q"], capture_output=True, text=True)
            if r.returncode != 0:
                print(f"{name}: exit {r.returncode}\n{r.stderr}", file=sys.stderr)
                return 1
            folder = os.path.join(out, name)
            current[name] = hash_outputs(folder)

    if args.update or args.add_machine:
        stored_runs = {name for m in sets for name in m["runs"]} if args.add_machine else set()
        not_run = sorted((stored_runs - current.keys()) | set(skipped))
        if not_run:
            print(f"not run here (no ../shared data?): {', '.join(not_run)}; a set without them checks less: "
                  "nothing stored", file=sys.stderr)
            return 1
        if args.add_machine and mine:
            if mine[0]["runs"] == current:
                print(f"this machine's hashes are stored already (at {mine[0].get('commit')}), and match")
                return 0
            print("this machine's outputs differ from the hashes already stored for it: if they changed on purpose, "
                  "use --update", file=sys.stderr)
            return 1
        kept = [m for m in sets if args.add_machine and (m["cpu"], m["isa"]) != (cpu, isa)]
        write_manifest(kept + [{"cpu": cpu, "isa": isa, "commit": source_commit(args.src),
                                "runs": current}])
        print(f"stored {sum(len(v) for v in current.values())} hashes from {len(current)} runs for this machine "
              f"in {MANIFEST} ({len(kept)} other machine kinds kept)")
        return 0

    if not mine:
        kinds = "; ".join(f"'{m['cpu']}' ({m['isa']})" for m in sets)
        print(f"no hashes stored for this machine, '{cpu}' ({isa}); stored for: {kinds}: skipped")
        return 77
    stored = mine[0]
    differ, missing = [], []
    for name, files in stored["runs"].items():
        if name not in current:
            missing.append(name)
            continue
        for rel, h in files.items():
            if current[name].get(rel) != h:
                differ.append(f"{name}/{rel}")
        for rel in current[name].keys() - files.keys():
            differ.append(f"{name}/{rel} (new output)")
    differ += [f"{name}/ (new run)" for name in sorted(current.keys() - stored["runs"].keys())]
    checked = sum(len(current.get(n, {})) for n in stored["runs"])
    if missing:
        print(f"not run (no ../shared data?): {', '.join(missing)}")
    if differ:
        print(f"{len(differ)} of {checked} outputs differ from the ones stored for this machine "
              f"(at {stored.get('commit', 'an unrecorded commit')}):\n  " + "\n  ".join(differ))
        return 1
    print(f"{checked} outputs bit-identical to the ones stored for this machine ({len(current)} runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
