#!/usr/bin/env python3
"""experiment.py's progress line (scripts/experiment_progress.py): its job list is the
workflow's, job for job, as Snakemake plans it (dry run of workflow/Snakefile, ~3 s a config);
the time left is the pending jobs' model rescaled by what this run's finished jobs took; the
refiner's window count is refiner_net.cpp's."""
import json
import os
import re
import shutil
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import experiment_lib as X  # noqa: E402
import experiment_progress as P  # noqa: E402


def snakemake_command(c, folder):
    """A Snakemake command of config c in `folder`, as experiment.py's (without its lock)."""
    config = os.path.join(folder, "config.json")
    with open(config, "w") as f:
        json.dump(c, f)
    return ["snakemake", "--snakefile", os.path.join(ROOT, "workflow", "Snakefile"), "--directory", folder,
            "--configfile", config, "--cores", "2", "--nolock"]


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
                want = P.pending_jobs(snakemake_command(c, d) + ["--forceall"])
                self.assertGreater(len(want), 10)
                self.assertEqual(sorted(rel for rel, _ in P.planned_jobs(c)), sorted(want))

    @unittest.skipUnless(shutil.which("snakemake"), "snakemake not installed")
    def test_a_narrowed_run_plans_its_own_jobs(self):
        # `-- --config 'fits=[eac]'` (docs/workflow.md): the e and ea fits' jobs are not the run's
        c = X.settings(paper=True, scenes=["veach-bidir"])
        with tempfile.TemporaryDirectory() as d:
            pending = P.pending_jobs(snakemake_command(c, d) + ["--config", "fits=[eac]"])
            narrowed = {rel for rel, _ in P.planned_jobs(c) if not re.search(r"_(e|ea)[_.]", rel)}
            self.assertIn("veach-bidir/benchmarks/fit_eac.tsv", narrowed)
            self.assertEqual(pending, narrowed)
            self.assertEqual(P.Progress(c, d, time.time(), pending).estimate()[:2], (0, len(pending)))
            self.assertIsNone(P.pending_jobs(snakemake_command(c, d) + ["--no-such-option"]))

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
        pending = [rel for rel, _ in self.jobs[1:]]  # the dry run's plan at the start
        for rel, s in mine:
            write_benchmark(os.path.join(self.dir, rel), 2 * s, since + 50)
        n, total, done_s, left_s, scale = P.Progress(self.c, self.dir, since, pending).estimate()
        self.assertEqual((n, total), (4, len(self.jobs)))
        self.assertAlmostEqual(scale, 2.0, places=3)
        # the benchmark files hold seconds to 0.1 ms, so the rescaling is 2 to about 1e-7
        left = 2 * sum(s for _, s in self.jobs[4:])
        self.assertAlmostEqual(left_s, left, delta=1e-6 * left)
        self.assertAlmostEqual(done_s, 10 * earlier[1] + sum(2 * s for _, s in mine), delta=1e-3)

    def test_earlier_jobs_calibrate_until_this_run_finishes_one(self):
        rel, s = self.jobs[0]
        write_benchmark(os.path.join(self.dir, rel), 3 * s, time.time() - 1000)
        self.assertAlmostEqual(P.Progress(self.c, self.dir, time.time()).estimate()[4], 3.0, places=3)
        self.assertAlmostEqual(P.Progress(self.c, os.path.join(self.dir, "empty"), time.time()).estimate()[4], 1.0)

    def test_a_rerun_job_is_pending_until_it_writes_its_file_again(self):
        since = time.time()
        (rel, s), = self.jobs[:1]
        write_benchmark(os.path.join(self.dir, rel), s, since - 1000)  # an old run's; its settings changed
        p = P.Progress(self.c, self.dir, since, [rel])
        self.assertEqual(p.estimate()[:2], (0, 1))
        self.assertAlmostEqual(p.estimate()[3], s, delta=1e-6)
        write_benchmark(os.path.join(self.dir, rel), 4 * s, since + 10)
        self.assertEqual(p.estimate()[:2], (1, 1))
        self.assertAlmostEqual(p.estimate()[4], 4.0, places=3)

    def test_lines(self):
        p = P.Progress(self.c, self.dir, time.time())
        self.assertIn(f"0 of {len(self.jobs)} jobs done", p.line())
        self.assertIn("until ~", p.line())
        self.assertIn("of job time (", P.Progress(self.c, self.dir, time.time(), clock=False).line())
        for rel, s in self.jobs:
            write_benchmark(os.path.join(self.dir, rel), s, time.time())
        self.assertRegex(p.line(), rf"^experiment: {len(self.jobs)} of {len(self.jobs)} jobs done \(\d+ (h \d+ )?min")
        self.assertEqual((P.duration(59 * 60), P.duration(61 * 60 + 20)), ("59 min", "1 h 01 min"))


class SequenceFiles(unittest.TestCase):
    @unittest.skipUnless(shutil.which("snakemake"), "snakemake not installed")
    def test_another_frame_count_rewrites_the_sequence_files(self):
        """<scene>/edits-<kind>.json and view-*.json follow the config: a run with another --frames
        in the same folder rewrites them (they had no params, and Snakemake reruns a run: rule only
        when its code changes, so the chunks rendered the old sequence's frames)."""
        import subprocess
        scene = X.settings(quick=True)["scenes"][0]
        targets = [f"{scene}/edits-camera.json", f"{scene}/view-novel.json"]
        with tempfile.TemporaryDirectory() as d:
            for frames in (3, 5, 3):
                c = X.settings(quick=True, frames=frames)
                subprocess.run(snakemake_command(c, d) + targets, check=True, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
                with open(os.path.join(d, targets[0])) as f:
                    self.assertEqual(json.load(f)["frames"], frames)
            with open(os.path.join(d, targets[1])) as f:  # unchanged by --frames: one frame
                self.assertEqual(json.load(f)["frames"], 1)


if __name__ == "__main__":
    unittest.main()
