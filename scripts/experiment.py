#!/usr/bin/env python3
"""The paper's ablation (Table 1) and per-frame error plots as one command, on the scenes in
../shared/scenes: the front of the Snakemake workflow workflow/Snakefile (docs/workflow.md),
which drives the latentpt binary. Local by default (--cores); --slurm submits every job to a
Slurm cluster instead. A stopped run continues where it stopped when started again with the
same flags: finished jobs are kept, killed ones resume (fits from their checkpoint, edit
sequences from their last finished frame). It prints how far the run is and about how long it
has left when it starts and after each job (scripts/experiment_progress.py).

For each scene: three stage-1 fits to the TAESD3-encoded RGB reference (terms e, ea, eac; the
eac fit also trains the refiner), then every edit sequence scenes/<scene>/edits-<kind>.json
(camera, light, object; 60 frames) rendered by each fit with path-traced references (traced once
per sequence, shared through --reference-cache). Results under --out (default results/):

    <scene>/fit_<terms>/              latentpt fit folders
    <scene>/<kind>_<terms>/           render --edit folders (frames, metrics_A-B.csv per job, metrics.csv)
    <scene>/refs/                     path-traced reference frames, shared by the fits
    <scene>/logs/, benchmarks/        each job's log and its time
    summary.md, summary.json          the ablation tables (summary.json: results only)
    timings.json                      job times per scene and stage
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
import fcntl
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment_lib as X  # noqa: E402
import experiment_progress as P  # noqa: E402


def snakemake_command(a, config_path, out):
    cmd = ["snakemake", "--snakefile", os.path.join(X.ROOT, "workflow", "Snakefile"), "--directory", out,
           "--configfile", config_path, "--rerun-incomplete", "--cores", str(a.cores),
           # our own lock (below) replaces Snakemake's, which a killed run leaves behind
           "--nolock"]
    if a.slurm:
        # Snakemake's generic cluster mode with our status script: its --slurm executor of 7.21
        # needs $USER and sacct accounting for status, which small clusters often lack.
        cmd += ["--cluster", "sbatch --parsable -J lpt-{rule} -c {threads} -o .snakemake/slurm-%j.out",
                "--cluster-status", os.path.join(X.ROOT, "workflow", "slurm_status.py"), "--cluster-cancel", "scancel",
                "--jobs", str(a.jobs), "--latency-wait", "30"]
    else:
        # `run:` jobs (edit files, metric merges, the summary) in threads of this process: as
        # subprocesses (Snakemake 7's local default) each one starts Python and re-reads the workflow
        cmd += ["--force-use-threads"]
    if a.redo:
        cmd += ["--forceall"]
    return cmd + a.snakemake_args


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def report_progress(progress, stop, every=15.0):
    """Until `stop` is set: after each finished job, a line of how far the run is and about how
    long it has left (scripts/experiment_progress.py)."""
    seen = len(progress.finished())
    while not stop.wait(every):
        n = len(progress.finished())
        if n != seen:
            seen = n
            print(progress.line(), file=sys.stderr, flush=True)


def run_workflow(cmd, lock, progress=None):
    """Run Snakemake in a process group of its own and return (its exit status, the stop signal
    received or None). A SIGINT, SIGTERM or SIGHUP to this process reaches the whole group as the
    SIGINT of a terminal's Ctrl-C: running jobs stop where they are (killed jobs resume on the next
    run) and Snakemake cancels its Slurm jobs. Snakemake alone would finish its running jobs first,
    and a parent that exits at once (Python's SIGTERM) would free the folder's lock with Snakemake
    still running, so this process waits for the group with the lock held. A second signal kills
    the group. Snakemake holds the lock too (an flock belongs to the open file, which it inherits):
    a SIGKILL to this process alone leaves Snakemake running, and a run started beside it would
    race it for the same files."""
    received, group = [], []

    def forward(signum, _frame):
        received.append(signum)
        stop(signal.SIGINT if len(received) == 1 else signal.SIGKILL)

    def stop(sig):
        try:
            if group:
                os.killpg(group[0], sig)
        except ProcessLookupError:  # the group has already gone
            pass

    # Handlers first: a signal that comes while Snakemake starts must not end this process alone.
    before = {s: signal.signal(s, forward) for s in STOP_SIGNALS}
    reporting = threading.Event()
    try:
        # A process group, not a session: a new session is also a new scheduler autogroup on
        # Linux. With one, experiment.quick beside four other tests (ctest -j2) took 336 s, with
        # the group 178 s (one run each, 2 cores; CI with a session: 680-725 s).
        p = subprocess.Popen(cmd, process_group=0, pass_fds=(lock.fileno(),))
        group.append(p.pid)
        if received:  # arrived before the group existed
            stop(signal.SIGINT)
        if progress:
            threading.Thread(target=report_progress, args=(progress, reporting), daemon=True).start()
        returncode = p.wait()
    finally:
        reporting.set()
        for s, handler in before.items():
            signal.signal(s, handler)
    return returncode, (received[0] if received else None)


def check_arguments(ap, a):
    """Refuses what would plan nothing or something else than asked: --frames -3 planned no edit
    jobs and the summary rule then emptied an earlier run's results; 0 meant the default."""
    if a.quick and a.paper:
        ap.error("--quick and --paper are two presets; give one (--paper with other flags overrides its values)")
    for flag in ("image_res", "frames", "ref_spp", "fit_iterations", "refiner_iterations", "frame_step", "spp",
                 "chunk", "cores", "jobs"):
        value = getattr(a, flag)
        if value is not None and value < 1:
            ap.error(f"--{flag.replace('_', '-')} must be >= 1, got {value}")
    if a.image_res is not None and a.image_res % 8:
        ap.error(f"--image-res must be a multiple of 8 (latents are 1/8 of it), got {a.image_res}")
    for flag in ("emission_decay", "emitter_response_decay"):
        value = getattr(a, flag)
        if value is not None and not (math.isfinite(value) and value >= 0):
            ap.error(f"--{flag.replace('_', '-')} must be a finite number >= 0, got {value}")
    if a.refiner_dropout is not None and not 0 <= a.refiner_dropout <= 0.99:
        ap.error(f"--refiner-dropout must be in [0, 0.99], got {a.refiner_dropout}")
    if os.path.exists(a.out) and not os.path.isdir(a.out):
        ap.error(f"--out {a.out} is a file; name a folder (new or an earlier run's)")


def exposure_list(text):
    """--exposures: comma-separated finite numbers > 0."""
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"comma-separated numbers, got '{text}'")
    if not all(math.isfinite(k) and k > 0 for k in values):
        raise argparse.ArgumentTypeError(f"finite numbers > 0, got '{text}'")
    return values


def is_dry_run(snakemake_args):
    """Snakemake's --dry-run, -n, or -n among combined short flags (-np)."""
    return any(x in ("--dry-run", "--dryrun") or (x.startswith("-") and not x.startswith("--") and "n" in x[1:])
               for x in snakemake_args)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="one scene, small and short; checks the ablation ordering (CI)")
    ap.add_argument("--paper", action="store_true",
                    help="the paper-scale preset (issue 16): cbox-specular at 1024² (128² latents), veach-bidir and "
                         "dining-room at 512², frames 0, 20, 40 at 512 spp, 3000 stage-1 iterations, 6000 refiner "
                         "steps with cosine decay, emitter response decay 1e-4, no baseline; other flags override its values "
                         "(docs/results.md)")
    ap.add_argument("--scenes", default=None, help="comma-separated subset of " + ", ".join(X.SCENES))
    ap.add_argument("--out", default=os.path.join(X.ROOT, "results"))
    ap.add_argument("--bin", default=os.path.join(X.ROOT, "build", "apps", "latentpt"))
    ap.add_argument("--shared", default=os.environ.get("LATENTPT_SHARED", os.path.join(X.ROOT, "..", "shared")))
    ap.add_argument("--image-res", type=int, default=None, help="square RGB resolution (latents: 1/8)")
    ap.add_argument("--frames", type=int, default=None, help="frames per edit sequence (default: the files', 60)")
    ap.add_argument("--ref-spp", type=int, default=None, help="samples per pixel of the RGB references (default: per scene, 128-256)")
    ap.add_argument("--fit-iterations", type=int, default=None)
    ap.add_argument("--refiner-iterations", type=int, default=None)
    ap.add_argument("--frame-step", type=int, default=None, help="evaluate every N-th frame of each edit sequence (default 1; --paper: 20)")
    ap.add_argument("--spp", type=int, default=64, help="latent samples per pixel of the edited frames")
    ap.add_argument("--param", choices=["code", "gain"], default=None,
                    help="every ablation fit's --param (default: the preset's, else code; docs/params.md (4))")
    ap.add_argument("--emission-decay", type=float, default=None,
                    help="every fit's --emission-decay (default: the preset's, else 0; docs/fitting.md (17))")
    ap.add_argument("--emitter-response-decay", type=float, default=None,
                    help="every fit's --emitter-response-decay (default: the preset's, else 0; docs/fitting.md (18))")
    ap.add_argument("--exposures", type=exposure_list, default=None,
                    help="every fit's --exposures, the light exposures its iterations cycle through, e.g. 1,0.5,1,2 "
                         "(default: the preset's, else 1 only; docs/fitting.md \"Exposure cycle\")")
    ap.add_argument("--refiner-latent-target", choices=["encoded", "compensated"], default=None,
                    help="the refiner target of the fits that refine (default: the preset's, else encoded; docs/refiner.md "
                         "\"Latent target\")")
    ap.add_argument("--refiner-dropout", type=float, default=None,
                    help="the refiner dropout of the fits that refine (default: the preset's, 0, else the fit's own, "
                         "0.1; docs/results.md \"No dropout, one view\")")
    ap.add_argument("--refiner-emitters", choices=["on", "off"], default=None,
                    help="train an emitter refiner beside each fit's refiner (default: the preset's, on, else off; "
                         "docs/refiner.md \"Emitter refiner\")")
    ap.add_argument("--second-references", action="store_true",
                    help="also trace every scored frame's reference again with another seed and add Table 1 against "
                         "these independent references (MSE less their noise) to the summary; costs about the edit "
                         "stage's time again (docs/metrics.md \"Reference noise\")")
    ap.add_argument("--chunk", type=int, default=8, help="frames per edit job (the unit a cluster spreads)")
    ap.add_argument("--cores", type=int, default=os.cpu_count(),
                    help="cores per job (every job uses all of them; locally: the machine's)")
    ap.add_argument("--slurm", action="store_true", help="submit the jobs to Slurm with sbatch (docs/workflow.md)")
    ap.add_argument("--jobs", type=int, default=16, help="with --slurm: jobs queued at once")
    ap.add_argument("--redo", action="store_true",
                    help="run every job again (Snakemake --forceall); each still continues from what its folder holds "
                         "(fit checkpoints, frames with the same key, cached references): for results from "
                         "scratch, give a new --out")
    ap.add_argument("snakemake_args", nargs="*", help="after --: passed to snakemake (e.g. -- --dry-run)")
    a = ap.parse_args()
    check_arguments(ap, a)
    c = X.settings(quick=a.quick, scenes=a.scenes.split(",") if a.scenes else None, out=a.out, bin=a.bin,
                   shared=a.shared, image_res=a.image_res, frames=a.frames, ref_spp=a.ref_spp,
                   fit_iterations=a.fit_iterations, refiner_iterations=a.refiner_iterations, spp=a.spp, chunk=a.chunk,
                   paper=a.paper, frame_step=a.frame_step, emission_decay=a.emission_decay, param=a.param,
                   emitter_response_decay=a.emitter_response_decay, second_references=a.second_references,
                   refiner_latent_target=a.refiner_latent_target, refiner_dropout=a.refiner_dropout,
                   refiner_emitters=None if a.refiner_emitters is None else a.refiner_emitters == "on",
                   exposures=a.exposures)
    for s in c["scenes"]:
        if s not in X.SCENES:
            sys.exit(f"experiment: unknown scene '{s}' (have {', '.join(X.SCENES)})")
        if not os.path.exists(X.scene_file(c, s)):
            print(f"experiment: {X.scene_file(c, s)} not found (set LATENTPT_SHARED or --shared)", file=sys.stderr)
            return 77  # ctest's SKIP_RETURN_CODE
    if not os.path.exists(c["bin"]):
        sys.exit(f"experiment: {c['bin']} not found (bash scripts/build.sh)")
    # latentpt finds the VAE and LPIPS weights through LATENTPT_SHARED: --shared must reach the
    # jobs (Snakemake's children, and through sbatch the cluster's), not only the scene paths
    os.environ["LATENTPT_SHARED"] = c["shared"]
    os.makedirs(c["out"], exist_ok=True)
    lock = open(os.path.join(c["out"], ".experiment.lock"), "w")
    try:  # the kernel frees it once this process and its Snakemake have ended, however (unlike Snakemake's lock)
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        sys.exit(f"experiment: {c['out']} is in use by another experiment run (or by the Snakemake of one whose "
                 "experiment.py was killed; it goes on to the end)")
    dry_run = is_dry_run(a.snakemake_args)
    # a dry run plans with its own copy: refiner_study.py and seed_spread.py read the folder's
    # experiment-config.json as the settings its results were made with
    config_path = os.path.join(c["out"], "experiment-config" + (".dry-run" if dry_run else "") + ".json")
    X.write_atomic(config_path, json.dumps(c, indent=1))
    started = time.time()
    # Locally one job runs at a time (each takes every core), so the jobs' times add up to the
    # run's; on Slurm they overlap, and the line says job time only.
    cmd = snakemake_command(a, config_path, c["out"])
    # a dry run's plan is its output: Snakemake prints it once, and no job will finish
    progress = P.Progress(c, c["out"], started, None if dry_run else P.pending_jobs(cmd), clock=not a.slurm)
    if not dry_run:
        print(progress.line(), file=sys.stderr, flush=True)
    returncode, stopped_by = run_workflow(cmd, lock, progress)
    if stopped_by is not None:
        print(f"experiment: stopped by {signal.Signals(stopped_by).name}; finished jobs are kept in {c['out']}: "
              "run again with the same flags to continue", file=sys.stderr)
        return 128 + stopped_by
    if returncode != 0:
        sys.exit(f"experiment: the workflow failed (exit {returncode}); job logs in {c['out']}/<scene>/logs; "
                 "run again with the same flags to continue")
    if dry_run:
        return 0
    print(progress.line(), file=sys.stderr, flush=True)  # the last job's line: the workflow has ended
    summary = os.path.join(c["out"], "summary.md")
    if not os.path.exists(summary):  # targets named after -- that leave the summary out
        print(f"experiment: the named targets are done; no {summary} yet (the whole workflow writes it)")
        return 0
    if os.path.getmtime(summary) < started:
        print(f"experiment: {summary} is from an earlier run (up to date, or left out by the targets named after --)")
    with open(summary) as f:
        print(f.read())
    with open(os.path.join(c["out"], "summary.json")) as f:
        failures = json.load(f)["failures"]
    print(f"wrote {c['out']}/summary.md, summary.json, timings.json, report.html and plots")
    if failures:
        print("experiment: ordering check FAILED:\n  " + "\n  ".join(failures), file=sys.stderr)
        return 1 if a.quick else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
