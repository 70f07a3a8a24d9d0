#!/usr/bin/env python3
"""workflow/slurm_status.py's verdicts from what scontrol and sacct answer (both replaced by
scripted answers, so no cluster is needed): a job purged by slurmctld whose accounting record
comes a moment later, sacct timing out, and a preempted job that Slurm will requeue."""
import contextlib
import io
import os
import subprocess
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "workflow"))
import slurm_status as S  # noqa: E402


def verdict(answers):
    """slurm_status's stdout for job 42, `answers` a list of (command name, result) consumed in
    order: a (rc, stdout, stderr) tuple, or an exception to raise."""
    queue = list(answers)

    def run(cmd):
        name, result = queue.pop(0)
        assert cmd[0] == name, (cmd, name)
        if isinstance(result, BaseException):
            raise result
        return result

    out = io.StringIO()
    saved = S.run, S.time.sleep, sys.argv
    S.run, S.time.sleep, sys.argv = run, (lambda s: None), ["slurm_status.py", "42"]
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            S.main()
    finally:
        S.run, S.time.sleep, sys.argv = saved
    return out.getvalue().strip()


UNKNOWN = ("scontrol", (1, "", "slurm_load_jobs error: Invalid job id specified"))


class Verdicts(unittest.TestCase):
    def test_a_finished_job(self):
        self.assertEqual(verdict([("scontrol", (0, "JobId=42 JobState=COMPLETED Requeue=0", ""))]), "success")

    def test_a_purged_job_whose_record_comes_late_is_not_failed_at_once(self):
        late = [UNKNOWN, ("sacct", (0, "", "")), UNKNOWN, ("sacct", (0, "COMPLETED\n", ""))]
        self.assertEqual(verdict(late), "success")
        never = [UNKNOWN, ("sacct", (0, "", ""))] * 5
        self.assertEqual(verdict(never), "failed")

    def test_sacct_timing_out_is_a_retry_not_a_traceback(self):
        slow = [UNKNOWN, ("sacct", subprocess.TimeoutExpired(["sacct"], 60))] * 4 + [
            UNKNOWN, ("sacct", (0, "TIMEOUT\n", ""))]
        self.assertEqual(verdict(slow), "failed")  # the job's own time limit: a real failure
        busy = [("scontrol", subprocess.TimeoutExpired(["scontrol"], 60)),
                ("sacct", subprocess.TimeoutExpired(["sacct"], 60))] * 5
        self.assertEqual(verdict(busy), "running")  # the controller unreachable: ask again later

    def test_a_preempted_job_slurm_requeues_is_running(self):
        self.assertEqual(verdict([("scontrol", (0, "JobId=42 JobState=PREEMPTED Requeue=1", ""))]), "running")
        self.assertEqual(verdict([("scontrol", (0, "JobId=42 JobState=PREEMPTED Requeue=0", ""))]), "failed")


if __name__ == "__main__":
    unittest.main()
