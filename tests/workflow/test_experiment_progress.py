#!/usr/bin/env python3
"""experiment.py's progress line (scripts/experiment_progress.py): its job list is the
workflow's, job for job, as Snakemake plans it (dry run of workflow/Snakefile, ~3 s a config);
the time left is the pending jobs' model rescaled by what this run's finished jobs took; the
refiner's window count is refiner_net.cpp's."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import experiment_lib as X  # noqa: E402
import experiment_progress as P  # noqa: E402


def snakemake_benchmarks(c, folder):
    """The benchmark files of every job Snakemake would run for config c from an empty folder."""
    config = os.path.join(folder, "config.json")
    with open(config, "w") as f:
        json.dump(c, f)
    snakefile = os.path.join(ROOT, "workflow", "Snakefile")
    out = subprocess.run(["snakemake", "--snakefile", snakefile, "--directory", folder, "--configfile", config,
                          "--dry-run", "--forceall", "--cores", "2"],
                         capture_output=True, text=True, check=True)
    return sorted(re.findall(r"^\s*benchmark: (\S+)$", out.stdout + out.stderr, re.M))


def write_benchmark(path, seconds, mtime):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("s\th:m:s\tmax_rss\n%.4f\t0:00:00\t1.0\n" % seconds)
    os.utime(path, (mtime, mtime))


class JobList(unittest.TestCase):
    @unittest.skipUnless(shutil.which("snakemake"), "snakemake not installed")
    def test_the_workflows_jobs_exactly(self):
        configs = {"quick": X.settings(quick=True), "paper": X.settings(paper=True),
                   "paper, second references": X.settings(paper=True, second_references=True),
                   "full, every 6th frame": X.settings(frame_step=6)}
        for label, c in configs.items():
            with self.subTest(label), tempfile.TemporaryDirectory() as d:
                want = snakemake_benchmarks(c, d)
                self.assertGreater(len(want), 10)
                self.assertEqual(sorted(rel for rel, _ in P.planned_jobs(c)), want)

    def test_every_job_costs_something_and_references_cost_the_eac_chunks(self):
        c = X.settings(paper=True)
        model = dict(P.planned_jobs(c))
        self.assertTrue(all(s > 0 for s in model.values()))
        b = "cbox-specular/benchmarks/"
        # frames 20 and 40 of each sequence are traced by the eac fit's chunk, at 1024² and 512 spp
        extra = model[b + "edit_camera_eac_0-40.tsv"] - model[b + "edit_camera_e_0-40.tsv"]
        self.assertGreater(extra, 2 * P.trace_s("cbox-specular", 1024, 512))
        self.assertGreater(model[b + "fit_eac.tsv"], model[b + "fit_e.tsv"] + 6000 * P.REFINER_STEP_S)

    def test_window_count_is_the_refiners(self):
        # refiner_net.cpp: origins every 4 pixels while a 32-pixel window fits, and one flush with the edge
        self.assertEqual([P.windows(n) for n in (16, 32, 33, 64, 128)], [1, 1, 4, 81, 625])


class TimeLeft(unittest.TestCase):
    def setUp(self):
        self.c = X.settings(paper=True, scenes=["veach-bidir"])
        self.jobs = P.planned_jobs(self.c)
        self.dir = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, self.dir)

    def test_rescaled_by_this_runs_finished_jobs(self):
        since = time.time() - 100
        earlier, mine = self.jobs[0], self.jobs[1:4]
        write_benchmark(os.path.join(self.dir, earlier[0]), 10 * earlier[1], since - 1000)  # a stopped run's job
        for rel, s in mine:
            write_benchmark(os.path.join(self.dir, rel), 2 * s, since + 50)
        n, total, done_s, left_s, scale = P.Progress(self.c, self.dir, since).estimate()
        self.assertEqual((n, total), (4, len(self.jobs)))
        self.assertAlmostEqual(scale, 2.0, places=3)
        self.assertAlmostEqual(left_s, 2 * sum(s for _, s in self.jobs[4:]), delta=1e-3)
        self.assertAlmostEqual(done_s, 10 * earlier[1] + sum(2 * s for _, s in mine), delta=1e-3)

    def test_earlier_jobs_calibrate_until_this_run_finishes_one(self):
        rel, s = self.jobs[0]
        write_benchmark(os.path.join(self.dir, rel), 3 * s, time.time() - 1000)
        self.assertAlmostEqual(P.Progress(self.c, self.dir, time.time()).estimate()[4], 3.0, places=3)
        self.assertAlmostEqual(P.Progress(self.c, os.path.join(self.dir, "empty"), time.time()).estimate()[4], 1.0)

    def test_lines(self):
        p = P.Progress(self.c, self.dir, time.time())
        self.assertIn(f"0 of {len(self.jobs)} jobs done", p.line())
        self.assertIn("until ~", p.line())
        self.assertIn("of job time (", P.Progress(self.c, self.dir, time.time(), clock=False).line())
        for rel, s in self.jobs:
            write_benchmark(os.path.join(self.dir, rel), s, time.time())
        self.assertRegex(p.line(), rf"^experiment: {len(self.jobs)} of {len(self.jobs)} jobs done \(\d+ (h \d+ )?min")
        self.assertEqual((P.duration(59 * 60), P.duration(61 * 60 + 20)), ("59 min", "1 h 01 min"))


if __name__ == "__main__":
    unittest.main()
