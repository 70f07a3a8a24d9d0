#!/usr/bin/env python3
"""A SIGTERM or SIGINT sent to scripts/experiment.py alone (a batch system's cancel, `kill`,
`timeout`) stops the whole run before experiment.py exits: no job or Snakemake process of it
is left running beside a run started next, and the folder's lock is free. experiment.py exits
with 128 + the signal and says how to continue. A SIGKILL to experiment.py alone leaves the folder
locked while its Snakemake goes on. The latentpt jobs are a stand-in script that
records its pid and sleeps, so the test costs no CPU (~5 s).

    tests/workflow/test_interrupt.py
Exit 77 (skipped) without snakemake or ../shared."""
import os
import shutil
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from processes import alive, gone_and_unlocked, group_members, kill_groups, lock_is_free, wait_until  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAKE_BINARY = """#!/bin/sh
echo $$ >> "$LPT_FAKE_PIDS"
exec sleep 300
"""


def job_pids(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [int(line) for line in f if line.strip()]


class Run:
    """One experiment.py run in a session of its own, its jobs the stand-in script."""

    def __init__(self, tmp, binary, name):
        self.out, self.pids, self.log = (os.path.join(tmp, name + suffix) for suffix in ("", ".pids", ".stderr"))
        self.env = dict(os.environ, LPT_FAKE_PIDS=self.pids)
        self.cmd = [sys.executable, os.path.join(ROOT, "scripts", "experiment.py"), "--quick", "--bin", binary,
                    "--out", self.out]
        with open(self.log, "w") as err:  # a file, not a pipe: a surviving Snakemake would hold a pipe open
            self.p = subprocess.Popen(self.cmd, env=self.env, stdout=subprocess.DEVNULL, stderr=err,
                                      start_new_session=True)
        self.groups = {self.p.pid}

    def wait_for_first_job(self):
        """The pids of the jobs running once the first has started, or None if experiment.py
        skipped (77)."""
        p = self.p
        if not wait_until(lambda: job_pids(self.pids) or p.poll() is not None, 120):
            raise AssertionError("no job started within 120 s")
        if p.poll() is not None:
            if p.returncode == 77:
                return None
            raise AssertionError(f"experiment.py ended before its first job ({p.returncode})")
        jobs = job_pids(self.pids)
        self.groups |= {os.getpgid(j) for j in jobs}
        return jobs

    def lock_is_free(self):
        return lock_is_free(self.out)

    def stderr(self):
        with open(self.log) as f:
            return f.read()

    def kill(self):
        """Leave nothing behind, also when a check fails."""
        kill_groups(self.groups)
        self.p.poll()


def stop_mid_job(tmp, binary, sig):
    """Start the experiment, wait for its first job, send `sig` to experiment.py alone, check
    that nothing of the run outlives it. Returns None, or 77 to skip."""
    name = signal.Signals(sig).name
    run = Run(tmp, binary, name)
    p = run.p
    try:
        jobs = run.wait_for_first_job()
        if jobs is None:
            return 77
        os.kill(p.pid, sig)
        try:
            p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"{name}: experiment.py still running 60 s after the signal")
        # Processes of the group that Snakemake did not wait for may take a moment to go.
        groups = run.groups
        wait_until(lambda: not any(alive(j) for j in jobs) and not any(group_members(g) for g in groups), 10)
        left = [j for j in jobs if alive(j)] + [f"group {g}: {group_members(g)}" for g in groups if group_members(g)]
    finally:
        run.kill()
    err = run.stderr()
    assert not left, f"{name}: the run outlived experiment.py: {left}"
    assert p.returncode == 128 + sig, f"{name}: exit {p.returncode}, expected {128 + sig}; stderr: {err}"
    assert "run again" in err, f"{name}: no word on how to continue: {err}"
    assert run.lock_is_free(), f"{name}: the folder is still locked"
    print(f"test_interrupt: {name} stopped {len(jobs)} job(s) and Snakemake before experiment.py exited "
          f"({p.returncode})")
    return None


def kill_alone(tmp, binary):
    """A SIGKILL to experiment.py alone (`kill -9`, an OOM kill) cannot reach its Snakemake, which
    goes on: the folder stays locked while it runs, so a second run is refused rather than racing
    it for the same files, and the lock is free once Snakemake has gone. Returns None, or 77."""
    run = Run(tmp, binary, "SIGKILL")
    try:
        if run.wait_for_first_job() is None:
            return 77
        os.kill(run.p.pid, signal.SIGKILL)
        run.p.wait()
        assert not run.lock_is_free(), "SIGKILL: the lock was freed with the run's Snakemake still running"
        second = subprocess.run(run.cmd, env=run.env, capture_output=True, text=True, timeout=120)
        assert second.returncode not in (0, 77) and "in use" in second.stderr, \
            f"SIGKILL: a second run beside the orphaned Snakemake was not refused ({second.returncode}): {second.stderr}"
    finally:
        run.kill()
    assert wait_until(lambda: gone_and_unlocked(run.groups, run.out), 10), \
        "SIGKILL: the run's processes or the folder's lock outlived the kill"
    print("test_interrupt: SIGKILL to experiment.py alone: the folder stayed locked until its Snakemake was gone; "
          "a second run was refused")
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
        if kill_alone(tmp, binary) == 77:
            return 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
