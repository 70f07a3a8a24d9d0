#!/usr/bin/env python3
"""The experiment workflow killed mid-way (SIGKILL to every process of it, as a crash would)
resumes without recomputing any finished fit or frame, and gives the summary.json of a run that
was never stopped (issue 20). Tiny settings: ~2 x 1 minute on 2 cores.

    tests/workflow/test_resume.py --bin build/apps/latentpt --out build/workflow-resume
Exit 77 (skipped) without snakemake or ../shared."""
import argparse
import glob
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from processes import gone_and_unlocked, groups_below, kill_groups, wait_until  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TINY = ["--quick", "--image-res", "64", "--frames", "4", "--chunk", "2", "--fit-iterations", "30",
        "--refiner-iterations", "10", "--ref-spp", "8", "--spp", "4"]


def experiment(a, out):
    return [sys.executable, os.path.join(ROOT, "scripts", "experiment.py"), *TINY, "--bin", a.bin, "--out", out]


def finished_marks(out):
    """mtime of every finished fit and frame."""
    files = glob.glob(os.path.join(out, "*", "fit_*", "fit.done")) + glob.glob(os.path.join(out, "*", "*_*", "frame_*.done"))
    return {f: os.stat(f).st_mtime_ns for f in files}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--bin", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    if not shutil.which("snakemake"):
        print("test_resume: snakemake not installed", file=sys.stderr)
        return 77
    shutil.rmtree(a.out, ignore_errors=True)
    whole, killed = os.path.join(a.out, "whole"), os.path.join(a.out, "killed")
    r = subprocess.run(experiment(a, whole), stdout=subprocess.DEVNULL)
    if r.returncode == 77:
        return 77
    assert r.returncode == 0, f"uninterrupted run failed ({r.returncode})"

    p = subprocess.Popen(experiment(a, killed), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    # Kill once the first edit chunk has finished one frame but not its sequence.
    while p.poll() is None and not glob.glob(os.path.join(killed, "*", "camera_eac", "frame_0000.done")):
        time.sleep(0.05)
    # experiment.py's group and its Snakemake's (a group of its own, with the jobs): killing the
    # first alone would leave Snakemake running beside the resumed run.
    groups = groups_below(p.pid)
    kill_groups(groups)
    p.wait()
    assert wait_until(lambda: gone_and_unlocked(groups, killed), 30), "the killed run's processes live on"
    before = finished_marks(killed)
    frames_before = [f for f in before if f.endswith("frame_0000.done")]
    assert frames_before, "the run ended before the kill; nothing was tested"
    assert not os.path.exists(os.path.join(killed, "summary.json")), "the run was not stopped mid-way"

    r = subprocess.run(experiment(a, killed), stdout=subprocess.DEVNULL)
    assert r.returncode == 0, f"resumed run failed ({r.returncode})"
    after = finished_marks(killed)
    redone = [f for f, t in before.items() if after.get(f) != t]
    assert not redone, f"finished work recomputed after the resume: {redone}"
    with open(os.path.join(whole, "summary.json")) as f1, open(os.path.join(killed, "summary.json")) as f2:
        assert f1.read() == f2.read(), "summary.json differs from the uninterrupted run's"
    print(f"test_resume: killed with {len(before)} fits/frames finished; none recomputed; summary.json identical")
    return 0


if __name__ == "__main__":
    sys.exit(main())
