#!/usr/bin/env python3
"""A SIGTERM or SIGINT sent to scripts/experiment.py alone (a batch system's cancel, `kill`,
`timeout`) stops the whole run before experiment.py exits: no job or Snakemake process of it
is left running beside a run started next, and the folder's lock is free. experiment.py exits
with 128 + the signal and says how to continue. The latentpt jobs are a stand-in script that
records its pid and sleeps, so the test costs no CPU (~5 s).

    tests/workflow/test_interrupt.py
Exit 77 (skipped) without snakemake or ../shared."""
import fcntl
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAKE_BINARY = """#!/bin/sh
echo $$ >> "$LPT_FAKE_PIDS"
exec sleep 300
"""


def process_state(pid):
    """(state letter, process group) of a process from /proc/<pid>/stat, or None once it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError):
        return None
    return fields[0], int(fields[2])


def alive(pid):
    """True while pid runs (a zombie has finished)."""
    state = process_state(pid)
    return state is not None and state[0] != "Z"


def group_members(pgid):
    """Running (not zombie) processes of process group pgid. kill(-pgid, 0) would count a
    zombie that init has not reaped yet."""
    states = {int(e): process_state(e) for e in os.listdir("/proc") if e.isdigit()}
    return [pid for pid, st in states.items() if st and st[0] != "Z" and st[1] == pgid]


def wait_until(condition, seconds):
    end = time.time() + seconds
    while time.time() < end:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def job_pids(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [int(line) for line in f if line.strip()]


def stop_mid_job(tmp, binary, sig):
    """Start the experiment, wait for its first job, send `sig` to experiment.py alone, check
    that nothing of the run outlives it. Returns None, or 77 to skip."""
    name = signal.Signals(sig).name
    out, pids, log = (os.path.join(tmp, name + suffix) for suffix in ("", ".pids", ".stderr"))
    env = dict(os.environ, LPT_FAKE_PIDS=pids)
    cmd = [sys.executable, os.path.join(ROOT, "scripts", "experiment.py"), "--quick", "--bin", binary, "--out", out]
    with open(log, "w") as err:  # a file, not a pipe: a surviving Snakemake would hold a pipe open
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    groups = {p.pid}
    try:
        if not wait_until(lambda: job_pids(pids) or p.poll() is not None, 120):
            raise AssertionError("no job started within 120 s")
        if p.poll() is not None:
            if p.returncode == 77:
                return 77
            raise AssertionError(f"experiment.py ended before its first job ({p.returncode})")
        jobs = job_pids(pids)
        groups |= {os.getpgid(j) for j in jobs}
        os.kill(p.pid, sig)
        try:
            p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"{name}: experiment.py still running 60 s after the signal")
        # Processes of the group that Snakemake did not wait for may take a moment to go.
        wait_until(lambda: not any(alive(j) for j in jobs) and not any(group_members(g) for g in groups), 10)
        left = [j for j in jobs if alive(j)] + [f"group {g}: {group_members(g)}" for g in groups if group_members(g)]
    finally:
        for g in groups:  # leave nothing behind when a check fails
            try:
                os.killpg(g, signal.SIGKILL)
            except ProcessLookupError:
                pass
        p.poll()
    with open(log) as f:
        err = f.read()
    assert not left, f"{name}: the run outlived experiment.py: {left}"
    assert p.returncode == 128 + sig, f"{name}: exit {p.returncode}, expected {128 + sig}; stderr: {err}"
    assert "run again" in err, f"{name}: no word on how to continue: {err}"
    with open(os.path.join(out, ".experiment.lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # raises if something still holds it
    print(f"test_interrupt: {name} stopped {len(jobs)} job(s) and Snakemake before experiment.py exited "
          f"({p.returncode})")
    return None


def main():
    if not shutil.which("snakemake"):
        print("test_interrupt: snakemake not installed", file=sys.stderr)
        return 77
    with tempfile.TemporaryDirectory() as tmp:
        binary = os.path.join(tmp, "latentpt")
        with open(binary, "w") as f:
            f.write(FAKE_BINARY)
        os.chmod(binary, 0o755)
        for sig in (signal.SIGTERM, signal.SIGINT):
            if stop_mid_job(tmp, binary, sig) == 77:
                return 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
