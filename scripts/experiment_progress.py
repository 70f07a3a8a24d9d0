"""How far an experiment run is and about how long it has left: experiment.py prints a line
when it starts and one after each finished job (docs/workflow.md "Progress").

Every job of the workflow that writes a benchmark file (workflow/Snakefile) gets a cost from a
model of its work: RGB samples traced, refiner steps and inference windows, frames decoded and
scored. The model's constants are seconds on one reference machine (the slow 2-core AMD EPYC of
sessions 38-40, idle); a run rescales them by the ratio of its finished jobs' measured times to
their modelled ones, so a faster or slower machine gets its own estimate after its first jobs.
The jobs a run will do are those Snakemake's dry run of the same command lists (targets,
--config and --forcerun after `--` included); a job is finished once it has written its
benchmark file, which Snakemake does when the job ends."""
import os
import re
import subprocess
import time

import experiment_lib as X

# Seconds per RGB pixel-sample of each scene's path tracer on 2 threads (32-spp renders, less the
# scene's loading; the latent renderer's 16-wide samples cost LATENT_FACTOR times as much), and
# seconds to load the scene (dining-room's 270k triangles), once per job.
TRACE_S = {"cbox-specular": 7.8e-7, "veach-bidir": 1.05e-6, "dining-room": 1.8e-6}
LOAD_S = {"dining-room": 3.0}
LATENT_FACTOR = 1.5
SCORE_S_PER_PIXEL = 1.15e-5  # an image decoded or encoded, scored (LPIPS, SSIM) and written, per RGB pixel
FRAME_SCORE_S_PER_PIXEL = 6.2e-6  # one latent of a `render --edit` frame, decoded once, scored and written
WINDOW_S = 0.04  # the refiner on one 32² latent window (inference, width 256)
WINDOW, WINDOW_STRIDE = 32, 4  # the refiner's inference windows (refiner/refiner_net.cpp)
REFINER_STEP_S = 0.165  # one training step of the main refiner
EMITTER_REFINER_S = 90.0  # `refine --emitters`' 3000 steps at expansion 4, with its renders
JOB_S = 8.0  # start-up: binary, plugins, networks, fit folder


def start_s(scene):
    """A job's start-up on this scene."""
    return JOB_S + LOAD_S.get(scene, 0.0)


def trace_s(scene, res, spp):
    return TRACE_S.get(scene, max(TRACE_S.values())) * res * res * spp


def score_s(res):
    return SCORE_S_PER_PIXEL * res * res


def frame_score_s(res):
    return FRAME_SCORE_S_PER_PIXEL * res * res


def windows(latent):
    """Inference windows over a latent side (refiner_net.cpp's window_origins), squared."""
    if latent <= WINDOW:
        return 1
    return (len(range(0, latent - WINDOW, WINDOW_STRIDE)) + 1) ** 2


def refined_frame_s(res):
    """What a refined frame adds to a rendered one: both refiners' windows, the refined latent
    decoded and scored."""
    return windows(res // 8) * WINDOW_S * 17 / 16 + 0.6 * frame_score_s(res)


def frame_s(c, scene, name, spp):
    """One frame of `render --edit`: the latent render, decoded and scored (and refined)."""
    res = X.image_res_of(c, scene)
    s = LATENT_FACTOR * trace_s(scene, res // 8, spp) + frame_score_s(res)
    return s + (refined_frame_s(res) if X.FITS[name][2] else 0.0)


def reference_s(c, scene, spp):
    """An edited frame's RGB reference: traced, encoded and written."""
    res = X.image_res_of(c, scene)
    return trace_s(scene, res, spp) + 1.7 * score_s(res)


def fit_s(c, scene, name):
    """Stage 1 at 4 spp per iteration, its final renders and scores; the refiners if it trains them."""
    res = X.image_res_of(c, scene)
    # stored-path replay (docs/path-replay.md) brings an iteration's 16-wide latent sample down to
    # about the cost of one RGB sample: measured on the three scenes' e and ea fits
    s = start_s(scene) + 10.0 + trace_s(scene, res // 8, 4 * c["fit_iterations"]) + score_s(res)
    if X.FITS[name][2]:
        s += c["refiner_iterations"] * REFINER_STEP_S + 3 * score_s(res) + 10.0
        s += EMITTER_REFINER_S if c.get("refiner_emitters") else 0.0
    return s


def edit_chunk_s(c, scene, kind, name, first, last):
    """A chunk of a sequence: its frames, and in the eac fit's job their references but frame 0's
    (the training view's, traced by the training-reference job). Frame 0 is rendered once per fit
    (render --frame-cache), counted in the first sequence's chunk; the others copy it."""
    frames = [f for f in X.frames_evaluated(c, scene, kind) if first <= f <= last]
    rendered = [f for f in frames if f != 0 or kind == X.KINDS[0]]
    s = start_s(scene) + len(rendered) * frame_s(c, scene, name, c["spp"])
    if name == "eac":
        s += sum(reference_s(c, scene, X.ref_spp_of(c, scene)) for f in frames if f != 0)
    return s


def equal_error_s(c, scene):
    """`bench --equal-error`: RGB renders at 1, 2, 4 ... max spp and latent ones up to a quarter of
    it, each encoded or decoded."""
    res, top = X.image_res_of(c, scene), c.get("equal_error_max_spp", 1024)
    levels = top.bit_length() + max(1, (top // 4).bit_length())
    return start_s(scene) + trace_s(scene, res, 2 * top - 1) + levels * score_s(res) / 3


def planned_jobs(c):
    """[(benchmark file relative to the run's folder, modelled seconds)] of every job of the
    workflow (workflow/Snakefile) for this config."""
    jobs = []
    for scene in c["scenes"]:
        res = X.image_res_of(c, scene)
        b = os.path.join(scene, "benchmarks")
        jobs.append((os.path.join(b, "reference_training.tsv"),
                     start_s(scene) + trace_s(scene, res, X.training_ref_spp_of(c, scene)) + score_s(res)))
        for name in X.fits_of(c):
            jobs.append((os.path.join(b, f"fit_{name}.tsv"), fit_s(c, scene, name)))
            for kind in X.KINDS:
                for first, last in X.chunks(c, scene, kind):
                    jobs.append((os.path.join(b, f"edit_{kind}_{name}_{first}-{last}.tsv"),
                                 edit_chunk_s(c, scene, kind, name, first, last)))
        for view in c.get("conv_views", ["training", "novel"]):
            for i, spp in enumerate(c["spp_list"]):
                copied = view == "training" and spp == c["spp"]  # the edit sequences' frame 0
                s = start_s(scene) + (0.0 if copied else frame_s(c, scene, "eac", spp))
                if view != "training" and i == 0:  # the first spp's job traces the view's reference
                    s += reference_s(c, scene, X.ref_spp_of(c, scene))
                jobs.append((os.path.join(b, f"conv_{view}_{spp}.tsv"), s))
        jobs.append((os.path.join(b, "equal_error.tsv"), equal_error_s(c, scene)))
        if c.get("second_references"):
            for kind in X.KINDS:
                frames = [f for f in X.frames_evaluated(c, scene, kind) if kind == "camera" or f != 0]
                per_frame = frame_s(c, scene, "eac", c["spp"]) + reference_s(c, scene, X.ref_spp_of(c, scene))
                jobs.append((os.path.join(b, f"noise_{kind}.tsv"), start_s(scene) + len(frames) * per_frame))
            scored = len(X.KINDS) * len(X.frames_evaluated(c, scene, X.KINDS[0])) * (len(X.fits_of(c)) + 1)
            jobs.append((os.path.join(b, "noise_scores.tsv"), start_s(scene) + scored * score_s(res) / 2))
    return jobs


def pending_jobs(snakemake_cmd):
    """The benchmark files (relative to the run's folder) of the jobs Snakemake would run for this
    command: its dry run's plan. None if the dry run fails (the run itself will say why)."""
    try:
        out = subprocess.run(snakemake_cmd + ["--dry-run"], capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if out.returncode != 0:
        return None
    return set(re.findall(r"^\s*benchmark: (\S+)$", out.stdout + out.stderr, re.M))


class Progress:
    """The run's state: `line()` says how far it is and, from the jobs finished so far, how long it
    has left. `since`: when this invocation began. `pending`: the benchmark files of the jobs it
    will run (pending_jobs; None: every planned job without one). A pending job is finished once
    it has written its file after `since` (Snakemake reruns jobs whose settings changed, over
    their old files); the other planned jobs with a file are an earlier run's, done, and
    calibrate the model only while none of this run's has finished."""

    def __init__(self, c, out, since, pending=None, clock=True):
        self.model, self.out, self.since, self.clock = dict(planned_jobs(c)), out, since, clock
        self.pending = set(pending) if pending is not None else {r for r in self.model if not self._measured(r)}
        self.typical = sum(self.model.values()) / max(1, len(self.model))  # a pending job the model lacks

    def _cost(self, rel):
        return self.model.get(rel, self.typical)

    def _measured(self, rel, after=None):
        """The job's measured seconds if its benchmark file exists (written after `after`), else None."""
        path = os.path.join(self.out, rel)
        try:
            if after is not None and os.path.getmtime(path) < after:
                return None
            return X.benchmark_seconds(path)
        except (OSError, ValueError, KeyError):  # not there yet, or being written
            return None

    def finished(self):
        """{benchmark path: (measured seconds, finished in this invocation)} of the done jobs."""
        done = {}
        for rel in self.pending | set(self.model):
            s = self._measured(rel, self.since if rel in self.pending else None)
            if s is not None:
                done[rel] = (s, rel in self.pending)
        return done

    def estimate(self):
        """(jobs done, jobs in all, measured seconds done, modelled seconds left × scale, scale)."""
        done = self.finished()
        ours = [rel for rel, (_, now) in done.items() if now] or list(done)
        scale = sum(done[r][0] for r in ours) / sum(self._cost(r) for r in ours) if ours else 1.0
        left = sum(self._cost(rel) for rel in self.pending if rel not in done)
        total = len(done) + len(self.pending - set(done))
        return len(done), total, sum(s for s, _ in done.values()), left * scale, scale

    def line(self, now=None):
        n, total, done_s, left_s, scale = self.estimate()
        now = time.time() if now is None else now
        if n == total:
            return f"experiment: {n} of {total} jobs done ({duration(done_s)} of job time)"
        until = f", until ~{time.strftime('%H:%M', time.localtime(now + left_s))}" if self.clock else " of job time"
        basis = f"job times modelled × {scale:.2f}" if n else \
            "the model's reference machine; rescaled after the first job"
        return (f"experiment: {n} of {total} jobs done ({duration(done_s)} of job time); about {duration(left_s)} "
                f"left{until} ({basis})")


def duration(seconds):
    m = int(round(seconds / 60))
    return f"{m // 60} h {m % 60:02d} min" if m >= 60 else f"{m} min"
