#!/usr/bin/env python3
"""Snakemake --cluster-status script for Slurm.

Usage: slurm_status.py JOBID   (JOBID as printed by `sbatch --parsable`)
Prints exactly one of: success, running, failed.

Uses `scontrol show job` first because a cluster without accounting (tests/slurm/cluster.sh)
runs without accounting storage, where `sacct` only says "accounting storage is
disabled". `sacct` is the fallback for jobs that slurmctld has already purged
(older than MinJobAge) on clusters that do have accounting.
Diagnostics go to stderr; snakemake reads only stdout.
"""
import re
import subprocess
import sys
import time

SUCCESS = {"COMPLETED"}
# Anything else that is not a final failure (PENDING, RUNNING, COMPLETING,
# CONFIGURING, SUSPENDED, REQUEUED, RESIZING, STAGE_OUT, ...) counts as running:
# the job may still produce its outputs.
FAILED = {
    "BOOT_FAIL", "CANCELLED", "DEADLINE", "FAILED", "NODE_FAIL",
    "OUT_OF_MEMORY", "PREEMPTED", "REVOKED", "SPECIAL_EXIT", "TIMEOUT",
}


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    return p.returncode, p.stdout, p.stderr


def scontrol_state(jobid):
    """(state or None, job_unknown). A preempted job that Slurm will requeue (Requeue=1) is
    RUNNING: it starts again and may still write its outputs, which Snakemake would otherwise
    delete as a failed job's."""
    rc, out, err = run(["scontrol", "-o", "show", "job", jobid])
    if rc != 0:
        return None, "Invalid job id" in err
    m = re.search(r"\bJobState=(\S+)", out)
    if m and m.group(1) == "PREEMPTED" and re.search(r"\bRequeue=1\b", out):
        return "RUNNING", False
    return (m.group(1) if m else None), False


def sacct_state(jobid):
    try:
        rc, out, _ = run(["sacct", "-X", "-n", "-P", "-o", "State", "-j", jobid])
    except (OSError, subprocess.TimeoutExpired) as e:  # not installed, or slurmdbd slow
        print(f"slurm_status: sacct: {e}", file=sys.stderr)
        return None
    if rc != 0 or not out.strip():
        return None
    # e.g. "CANCELLED by 0" -> "CANCELLED"
    return out.strip().splitlines()[0].split()[0]


def classify(state):
    base = state.split("+")[0]
    if base in SUCCESS:
        return "success"
    if base in FAILED:
        return "failed"
    return "running"


def main():
    if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    # `sbatch --parsable` may print "jobid;cluster".
    jobid = sys.argv[1].split(";")[0].strip()

    # Retry transient failures (slurmctld busy or restarting, accounting not yet written for a
    # job slurmctld has just purged) before judging.
    unknown = False
    for attempt in range(5):
        try:
            state, unknown = scontrol_state(jobid)
        except (OSError, subprocess.TimeoutExpired) as e:
            state, unknown = None, False
            print(f"slurm_status: scontrol: {e}", file=sys.stderr)
        if state is None:
            state = sacct_state(jobid)
        if state is not None:
            print(classify(state))
            return 0
        time.sleep(1 + attempt)
    if unknown:
        # Purged by slurmctld and no accounting record: the outcome is lost.
        print(f"slurm_status: job {jobid} unknown to scontrol and sacct", file=sys.stderr)
        print("failed")
        return 0
    # Controller unreachable: report running so snakemake asks again later.
    print(f"slurm_status: cannot query job {jobid}; assuming running",
          file=sys.stderr)
    print("running")
    return 0


if __name__ == "__main__":
    sys.exit(main())
