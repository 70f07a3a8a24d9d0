#!/usr/bin/env python3
"""`import latentpt` from the build tree: scenes, latent renders, the torch autograd function
against finite differences, the pipeline with a progress callback and a cancel, and torch and
latentpt in one process. Run by ctest (python.module) with PYTHONPATH=<build>/python."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import unittest

import numpy as np

import latentpt

SRC = os.environ.get("LATENTPT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BOX = os.path.join(SRC, "scenes", "cornell-box", "scene.json")
# Russian roulette off and short paths: every sampling decision is independent of the latent
# values, so the primal with fixed random numbers is smooth in them and central differences apply.
SMOOTH = {"integrator.max_depth": "3", "integrator.rr_depth": "100", "camera.width": "8", "camera.height": "8"}


def torch_or_skip():
    try:
        import torch  # noqa: F401
        import latentpt.torch  # noqa: F401
        return torch
    except ImportError as e:
        raise unittest.SkipTest(f"torch is not importable: {e}")


class SceneTest(unittest.TestCase):
    def test_render_is_an_array_of_the_asked_size(self):
        scene = latentpt.Scene(BOX)
        img = scene.render(spp=2, width=24, height=16)
        self.assertEqual(img.shape, (16, 24, 3))
        self.assertEqual(img.dtype, np.float32)
        self.assertTrue(np.isfinite(img).all())
        self.assertGreater(img.mean(), 0.0)
        np.testing.assert_array_equal(img, scene.render(spp=2, width=24, height=16))  # deterministic seed

    def test_bad_scene_raises_with_the_file_name(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "bad.json")
            with open(path, "w") as f:
                f.write('{"camera": {"fov": 40}, "shapes": [{"type": "obj", "filename": "nope.obj", "material": "m"}],'
                        ' "materials": {"m": {"type": "diffuse"}}}')
            with self.assertRaises(latentpt.SceneError) as ctx:
                latentpt.Scene(path)
            self.assertIn("nope.obj", str(ctx.exception))

    def test_defines_override_scene_values(self):
        scene = latentpt.Scene(BOX, defines={"camera.width": "10", "camera.height": "6"})
        self.assertEqual((scene.width, scene.height), (10, 6))


class LatentTest(unittest.TestCase):
    def setUp(self):
        self.model = latentpt.LatentScene(latentpt.Scene(BOX, defines=SMOOTH), seed=3)

    def test_named_values_round_trip(self):
        names = [s["name"] for s in self.model.slices()]
        self.assertIn("light.Le", names)
        v = np.linspace(-0.5, 0.5, 16, dtype=np.float32)
        self.model.set_value("floor.La", v)
        np.testing.assert_allclose(self.model.value("floor.La"), v, atol=1e-6)
        with self.assertRaises(KeyError):
            self.model.value("no.such")

    def test_misshapen_arrays_bad_values_and_spp_are_refused_and_change_nothing(self):
        m = self.model
        w = np.ones((m.height, m.width, 16), np.float32)
        with self.assertRaisesRegex(ValueError, r"d_linear: expected an array of shape \(8, 8, 16\)"):
            m.backward_linear(w.transpose(2, 0, 1).copy(), spp=2)  # channels first, as torch users write
        raw = m.raw.copy()
        with self.assertRaisesRegex(ValueError, "raw: expected an array of shape"):
            m.raw = raw.reshape(-1, 1)
        bad = raw.copy()
        bad[3] = np.nan
        with self.assertRaisesRegex(ValueError, r"raw: the value at \(3,\) is not finite"):
            m.raw = bad
        v = np.linspace(0.1, 0.5, 16, dtype=np.float32)
        v[-1] = np.nan  # refused at the last channel: the channels before it stay as they were
        with self.assertRaises(ValueError):
            m.set_value("red_wall.bsdf.reflectance", v)
        np.testing.assert_array_equal(m.raw, raw)
        for call in (lambda: m.render(spp=0), lambda: m.backward_linear(w, spp=-1),
                     lambda: m.scene.aovs(spp=0), lambda: m.scene.render(spp=-2)):
            with self.assertRaisesRegex(ValueError, "spp must be > 0"):
                call()

    def test_bad_model_and_render_arguments_are_refused_by_name(self):
        scene = self.model.scene
        with self.assertRaisesRegex(TypeError, "got None"):  # was a segmentation fault
            latentpt.LatentScene(None)
        with self.assertRaisesRegex(ValueError, "terms take letters from e, a, c; got 'xyz'"):
            latentpt.LatentScene(scene, terms="xyz")  # rendered zeros
        with self.assertRaisesRegex(ValueError, "gate is shadowed or visible, got 'visble'"):
            latentpt.LatentScene(scene, gate="visble")  # meant shadowed
        with self.assertRaisesRegex(ValueError, "width and height"):
            latentpt.LatentScene(scene, width=-4)
        for call in (lambda: scene.render(spp=1, width=-4), lambda: scene.aovs(height=-1)):
            with self.assertRaisesRegex(ValueError, "width and height must be >= 0"):
                call()  # the scene's size, without a word
        with self.assertRaisesRegex(ValueError, "max_depth must be >= -1"):
            scene.render(spp=1, max_depth=-5)

    def test_renders_and_parameter_changes_from_several_threads_do_not_race(self):
        """A render in one thread and raw writes in another: every render is of one raw vector."""
        m = self.model
        raws = [m.raw.copy(), m.raw.copy() * 0.5]
        expected = []
        for r in raws:
            m.raw = r
            expected.append(m.render_linear(spp=2, seed=1))
        got, stop = [], threading.Event()

        def writer():
            while not stop.is_set():
                for r in raws:
                    m.raw = r

        t = threading.Thread(target=writer)
        t.start()
        try:
            for _ in range(20):
                got.append(m.render_linear(spp=2, seed=1))
        finally:
            stop.set()
            t.join()
        for g in got:
            self.assertTrue(any(np.array_equal(g, e) for e in expected), "a render of half-written parameters")

    def check_against_central_differences(self, m, loss, grad, entries, what="adjoint"):
        """`grad` (of `loss`, a function of m's raw parameters) against central differences at the
        raw entries `entries` ({slice name: offsets within its raw})."""
        raw0 = m.raw.copy()
        checked = 0
        for s in m.slices():
            for k in entries.get(s["name"], ()):
                i, h = s["raw_offset"] + k, 1e-2
                up, down = raw0.copy(), raw0.copy()
                up[i] += h
                down[i] -= h
                m.raw = up
                lp = loss()
                m.raw = down
                lm = loss()
                fd = (lp - lm) / (2 * h)
                self.assertLess(abs(grad[i] - fd), 2e-2 * max(1.0, abs(fd)), f"{s['name']}[{k}]: {what} {grad[i]} fd {fd}")
                checked += 1
        m.raw = raw0
        self.assertEqual(checked, sum(len(v) for v in entries.values()))

    def check_adjoint(self, m, entries):
        """Raw gradient of a fixed linear functional of the linear latent against central
        differences, at the raw entries `entries` ({slice name: offsets within its raw})."""
        rng = np.random.default_rng(1)
        w = rng.uniform(-1, 1, (m.height, m.width, 16)).astype(np.float32)
        # Before the tone curve: its x^(1/2.2) is singular at 0, where fresh L̃a values start.
        loss = lambda: float((w * m.render_linear(spp=4, seed=7)).sum(dtype=np.float64))  # noqa: E731
        self.check_against_central_differences(m, loss, m.backward_linear(w, spp=4, seed=7), entries)

    def test_adjoint_matches_central_differences(self):
        names = ("light.Le", "floor.La", "back.Lc", "red_wall.bsdf.reflectance", "background")
        self.check_adjoint(self.model, {n: (0, 5) for n in names})

    def test_gain_adjoint_matches_central_differences(self):
        """param="gain" (docs/params.md (4)): the light's L̃e = e^g·u; raw entry 16 is g."""
        m = latentpt.LatentScene(latentpt.Scene(BOX, defines=SMOOTH), param="gain", seed=3)
        le = next(s for s in m.slices() if s["name"] == "light.Le")
        self.assertEqual((le["map"], le["raw_size"]), ("gain", 17))
        raw = m.raw.copy()
        raw[le["raw_offset"] + 16] = 0.5  # away from g = 0, where ∂v/∂u = 1
        m.raw = raw
        np.testing.assert_allclose(m.value("light.Le"), np.exp(0.5) * raw[le["raw_offset"]:le["raw_offset"] + 16],
                                   rtol=1e-6)
        self.check_adjoint(m, {"light.Le": (0, 5, 16), "floor.La": (0,)})
        raw[le["raw_offset"] + 16] = 50.0  # e^50 overflows float: refused, the model untouched
        with self.assertRaisesRegex(ValueError, "light.Le"):
            m.raw = raw
        self.assertAlmostEqual(float(m.raw[le["raw_offset"] + 16]), 0.5, places=6)

    def test_torch_gradient_matches_central_differences_through_the_tone_curve(self):
        """End to end: ∂(Σ w·latent)/∂raw from render_latent's backward against central differences
        of the tone-mapped render itself. w is zero where the linear latent is near the curve's
        singular 0 or its clamp at 3, where a difference quotient would not be a derivative."""
        torch = torch_or_skip()
        import latentpt.torch as lt
        m = self.model
        raw = lt.raw_parameters(m)
        linear = m.render_linear(spp=4, seed=7)
        usable = (np.abs(linear) > 0.05) & (np.abs(linear) < 2.5)
        self.assertGreater(usable.mean(), 0.3)
        w = (np.random.default_rng(3).uniform(-1, 1, linear.shape) * usable).astype(np.float32)
        (torch.from_numpy(w) * lt.render_latent(m, raw, spp=4, seed=7)).sum().backward()
        loss = lambda: float((w * m.render(spp=4, seed=7)).sum(dtype=np.float64))  # noqa: E731
        entries = {"light.Le": (0, 5), "floor.La": (0,), "back.Lc": (3,), "red_wall.bsdf.reflectance": (0,)}
        self.check_against_central_differences(m, loss, raw.grad.numpy(), entries, "autograd")

    def test_torch_function_backward_is_the_adjoint(self):
        torch = torch_or_skip()
        import latentpt.torch as lt
        m = self.model
        raw = lt.raw_parameters(m)
        latent = lt.render_latent(m, raw, spp=4, seed=7)
        self.assertEqual(tuple(latent.shape), (m.height, m.width, 16))
        w = torch.from_numpy(np.random.default_rng(2).uniform(-1, 1, tuple(latent.shape)).astype(np.float32))
        (w * latent).sum().backward()
        m.raw = raw.detach().numpy()
        expected = m.backward_linear(m.tone_backward(m.render_linear(spp=4, seed=7), w.numpy()), spp=4, seed=7)
        np.testing.assert_allclose(raw.grad.numpy(), expected, rtol=1e-6, atol=1e-9)
        # float64 parameters give a float64 latent and gradient, as torch functions answer
        raw64 = lt.raw_parameters(m).detach().double().requires_grad_()
        latent64 = lt.render_latent(m, raw64, spp=4, seed=7)
        self.assertEqual(latent64.dtype, torch.float64)
        (w.double() * latent64).sum().backward()
        self.assertEqual(raw64.grad.dtype, torch.float64)
        np.testing.assert_allclose(raw64.grad.numpy(), expected, rtol=1e-5, atol=1e-8)
        with self.assertRaisesRegex(TypeError, "floating-point torch.Tensor, got torch.int64"):
            lt.render_latent(m, raw.detach().long(), spp=1)  # was a latent truncated to integers


class VaeTest(unittest.TestCase):
    def test_arrays_the_vae_cannot_read_are_refused_by_name(self):
        shared = os.environ.get("LATENTPT_SHARED", os.path.join(SRC, "..", "shared"))
        if not os.path.exists(os.path.join(shared, "models", "taesd3", "taesd3_encoder.safetensors")):
            self.skipTest("no TAESD3 weights in ../shared")
        vae = latentpt.Vae(os.path.join(shared, "models", "taesd3"))
        grey = np.full((16, 16, 3), 0.5, np.float32)
        self.assertEqual(vae.encode(grey).shape, (2, 2, 16))
        bad = grey.copy()
        bad[1, 2, 0] = np.nan  # passed through as NaN latents
        with self.assertRaisesRegex(ValueError, r"encode: rgb: the value at \(1, 2, 0\) is not finite"):
            vae.encode(bad)
        vae.encode(np.clip(vae.decode(vae.encode(grey)) * 1.15 - 0.05, -0.2, 1.3))  # decoded: not clamped
        with self.assertRaisesRegex(ValueError, r"display values, about \[0, 1\].*divide by 255"):
            vae.encode(np.full((16, 16, 3), 200, np.uint8))  # latents of +-700
        with self.assertRaisesRegex(ValueError, "at least 8x8, got 0x0"):
            vae.encode(np.zeros((0, 0, 3), np.float32))  # torch's C++ stack trace
        latent = vae.encode(grey)
        latent[0, 1, 3] = np.inf
        with self.assertRaisesRegex(ValueError, r"decode: latent: the value at \(0, 1, 3\) is not finite"):
            vae.decode(latent)
        with self.assertRaisesRegex(ValueError, "decode: the latent is empty"):
            vae.decode(np.zeros((0, 2, 16), np.float32))


class GuidanceTest(unittest.TestCase):
    """An SDS-shaped loop with a stand-in guide: the latent pixels where one object is seen are
    pulled towards the VAE encoding of a flat colour. Like the paper's teapot example, the
    object's own parameters should take the change and everything else stay nearly put."""

    def test_guide_moves_the_seen_object_and_little_else(self):
        torch = torch_or_skip()
        import latentpt.torch as lt
        shared = os.environ.get("LATENTPT_SHARED", os.path.join(SRC, "..", "shared"))
        if not os.path.exists(os.path.join(shared, "models", "taesd3", "taesd3_encoder.safetensors")):
            self.skipTest("no TAESD3 weights in ../shared")
        defines = dict(SMOOTH, **{"camera.width": "16", "camera.height": "16"})
        m = latentpt.LatentScene(latentpt.Scene(defines=defines, path=BOX), seed=3)
        # Where the short block is seen: the pixels its L̃a reaches.
        before = m.render_linear(spp=4, seed=1)
        m.set_value("short_block.La", np.full(16, 5.0, np.float32))
        mask = np.abs(m.render_linear(spp=4, seed=1) - before).max(axis=2) > 1e-3
        m.set_value("short_block.La", np.zeros(16, np.float32))
        self.assertGreater(mask.sum(), 3)
        red = np.zeros((128, 128, 3), np.float32)
        red[..., 0] = 0.8
        target = torch.from_numpy(latentpt.Vae(os.path.join(shared, "models", "taesd3")).encode(red))
        mask_t = torch.from_numpy(mask)
        raw = lt.raw_parameters(m)
        start = raw.detach().clone()

        def guide_loss(r, spp, seed):
            return ((lt.render_latent(m, r, spp=spp, seed=seed) - target)[mask_t] ** 2).mean()

        # Judged on one 64-spp render with fixed random numbers before and after: the 4-spp losses
        # of the loop itself are too noisy to compare a few steps of.
        with torch.no_grad():
            before_loss = float(guide_loss(start, 64, 12345))
        # Plain gradient steps: Adam would move every parameter with any gradient at the same rate.
        # lr 0.1: at 0.5 the loop overshoots and its loss climbs back (3.6 -> 0.65 -> 1.8).
        opt = torch.optim.SGD([raw], lr=0.1)
        for it in range(30):
            opt.zero_grad()
            guide_loss(raw, 4, it).backward()
            opt.step()
        with torch.no_grad():
            after_loss = float(guide_loss(raw.detach(), 64, 12345))
        # Measured 0.07-0.12 of the start over five seed offsets.
        self.assertLess(after_loss, 0.25 * before_loss, (before_loss, after_loss))
        moved = (raw.detach() - start).abs().numpy()
        own = np.zeros(moved.size, bool)
        for s in m.slices():
            if s["name"].startswith("short_block."):
                own[s["raw_offset"]:s["raw_offset"] + s["raw_size"]] = True
        ratio = moved[own].mean() / max(moved[~own].mean(), 1e-12)
        self.assertGreater(ratio, 5.0, f"the block's parameters moved {moved[own].mean():.4f}, the rest "
                                       f"{moved[~own].mean():.4f}")


class GateCoverageTest(unittest.TestCase):
    """scripts/gate_coverage.py measures Ĩc's gate through the linear terms alone."""

    def test_shadowed_and_visible_gates_split_every_shape_and_the_ceiling_never_sees_the_light(self):
        import importlib.util
        spec = importlib.util.spec_from_file_location("gate_coverage", os.path.join(SRC, "scripts", "gate_coverage.py"))
        gc = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(gc)
        scene = latentpt.Scene(BOX, defines={"camera.width": "64", "camera.height": "64"})
        cover = {gate: gc.gate_coverage(latentpt.LatentScene(scene, seed=1, gate=gate), spp=2, seed=4)
                 for gate in ("shadowed", "visible")}
        gc.GROUP = 3  # shapes in groups of 3: the same paths, the same numbers
        grouped = gc.gate_coverage(latentpt.LatentScene(scene, seed=1, gate="shadowed"), spp=2, seed=4)
        for shape, (share, shadowed) in grouped.items():
            self.assertAlmostEqual(share, cover["shadowed"][shape][0], places=6, msg=shape)
            self.assertAlmostEqual(shadowed, cover["shadowed"][shape][1], places=6, msg=shape)
        self.assertEqual(set(cover["shadowed"]), {"floor", "ceiling", "back", "green_wall", "red_wall", "short_block",
                                                  "tall_block", "light"})
        for shape, (share, shadowed) in cover["shadowed"].items():
            # Same paths, complementary gates: every first vertex is counted by exactly one.
            self.assertAlmostEqual(shadowed + cover["visible"][shape][1], 1.0, places=5, msg=shape)
            self.assertAlmostEqual(share, cover["visible"][shape][0], places=6, msg=shape)
        # The light faces down from the ceiling: every ceiling sample lies on its back side.
        self.assertAlmostEqual(cover["shadowed"]["ceiling"][1], 1.0, places=6)
        self.assertLess(cover["shadowed"]["back"][1], 0.5)  # mostly lit; the blocks shadow a part
        self.assertGreater(cover["shadowed"]["back"][1], 0.0)
        self.assertAlmostEqual(sum(share for share, _ in cover["shadowed"].values()), 1.0, places=6)


class PipelineTest(unittest.TestCase):
    def test_options_the_cli_would_refuse_are_refused_by_name(self):
        small = dict(synthetic_res="8x8", iterations=2, spp=1, final_spp=1, refiner=False, note=lambda t: None)
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "fit")
            for options, error, words in (
                    (dict(seed=-1), ValueError, "option 'seed' = -1 is out of its range"),  # "cannot be a int"
                    (dict(iterations=True), TypeError, "option 'iterations' cannot be a bool"),  # ran 1
                    (dict(encode_res="64x64"), ValueError, "'encode_res' needs encode=True"),
                    (dict(restart_if_changed=True), ValueError, "'restart_if_changed' needs resume=True"),
                    (dict(progress=lambda p: "stop"), TypeError, "progress callback must return True, False"),
                    (dict(terms=1), TypeError, "option 'terms' cannot be a int")):
                with self.assertRaisesRegex(error, words):
                    latentpt.fit(BOX, out, **dict(small, **options))
            # options at their defaults are no request: a wrapper may pass them all
            latentpt.fit(BOX, out, **dict(small, restart_if_changed=False, encode_res="256x256", ref_spp=256))
            with self.assertRaisesRegex(ValueError, "the output folder is empty"):  # a filesystem error
                latentpt.fit(BOX, "", **small)
            with open(os.path.join(d, "file"), "w"):
                pass
            with self.assertRaisesRegex(ValueError, "a file, not a folder"):
                latentpt.fit(BOX, os.path.join(d, "file"), **small)

    def test_fit_reports_progress_and_cancels_cleanly(self):
        with tempfile.TemporaryDirectory() as d:
            steps = []
            summary = latentpt.fit(BOX, os.path.join(d, "fit"), defines={"integrator.max_depth": "3"},
                                   progress=lambda p: steps.append(p["step"]), note=lambda t: None,
                                   synthetic_res="8x8", iterations=12, spp=2, final_spp=4, refiner=False)
            self.assertEqual(steps, list(range(1, 13)))
            self.assertEqual(summary["iterations_run"], 12)
            model = latentpt.LatentScene.from_fit(os.path.join(d, "fit"))
            self.assertEqual(model.render(spp=2).shape, (8, 8, 16))
            cancelled = os.path.join(d, "cancelled")
            with self.assertRaises(latentpt.Cancelled):
                latentpt.fit(BOX, cancelled, progress=lambda p: p["step"] < 5, note=lambda t: None,
                             synthetic_res="8x8", iterations=12, spp=2, refiner=False)
            self.assertFalse(os.path.exists(os.path.join(cancelled, "params.json")))
            session = latentpt.EditSession(os.path.join(d, "fit"), os.path.join(SRC, "scenes", "cornell-box", "edits-demo.json"))
            self.assertEqual(session.frames, 8)
            frame = session.frame(3, spp=2)
            self.assertEqual(frame["latent"].shape, (8, 8, 16))
            self.assertIsNone(frame["refined"])  # this fit ran without a refiner
            self.assertFalse(np.array_equal(frame["latent"], session.frame(0, spp=2)["latent"]))
            # frame() lets other Python threads run; frames asked for from several at once come out
            # as serial calls render them (each call edits the session's one scene)
            serial = [session.frame(i, spp=2)["latent"] for i in range(session.frames)]
            for _ in range(4):  # unguarded, one round in three crashed in Embree
                together = [None] * session.frames
                threads = [threading.Thread(target=lambda i=i: together.__setitem__(i, session.frame(i, spp=2)["latent"]))
                           for i in range(session.frames)]
                for t in threads:
                    t.start()
                for t in threads:
                    t.join()
                for i in range(session.frames):
                    np.testing.assert_array_equal(together[i], serial[i], err_msg=f"frame {i}")
            shared = os.environ.get("LATENTPT_SHARED", os.path.join(SRC, "..", "shared"))
            if os.path.exists(os.path.join(shared, "models", "taesd3", "taesd3_decoder.safetensors")):
                rgb = latentpt.Vae.from_fit(os.path.join(d, "fit")).decode(frame["latent"])
                self.assertEqual(rgb.shape, (64, 64, 3))
                self.assertTrue(np.isfinite(rgb).all())
            with self.assertRaises(TypeError):
                latentpt.fit(BOX, cancelled, no_such_option=1)
            with self.assertRaisesRegex(TypeError, "option 'iterations' cannot be a str"):
                latentpt.fit(BOX, cancelled, synthetic_res="8x8", iterations="10")
            for bad, flag in (({"spp": -3}, "--spp"), ({"lr_period": 0}, "--lr-period"),
                              ({"exposures": [1, 0]}, "--exposures"), ({"exposures": [1, 2]}, "needs --encode")):
                with self.assertRaisesRegex(ValueError, flag):  # the fit's own checks, not only the CLI's
                    latentpt.fit(BOX, os.path.join(d, "never"), synthetic_res="8x8", refiner=False, **bad)
            self.assertFalse(os.path.exists(os.path.join(d, "never", "params.json")))


class SamplerTest(unittest.TestCase):
    """`sampler=` (the CLI's --sampler) belongs to the scene or fit it is given to, not to the process:
    each call must render exactly what the scene file's own `integrator.sampler` renders."""

    INDEPENDENT = {"integrator.sampler": "independent"}  # the file's own choice, as a -D value

    def test_a_scene_renders_with_its_own_sampler(self):
        args = dict(spp=4, width=16, height=16, seed=3)
        sobol, chosen = latentpt.Scene(BOX), latentpt.Scene(BOX, sampler="independent")
        self.assertEqual((sobol.sampler, chosen.sampler), ("sobol", "independent"))
        by_file = latentpt.Scene(BOX, defines=self.INDEPENDENT).render(**args)
        np.testing.assert_array_equal(chosen.render(**args), by_file)
        self.assertFalse(np.array_equal(sobol.render(**args), by_file))  # the other scene kept its own
        sobol.sampler = "independent"
        np.testing.assert_array_equal(sobol.render(**args), by_file)
        aovs = dict(spp=2, width=16, height=16, seed=3)  # the AOVs' samples follow it too
        self.assertFalse(np.array_equal(latentpt.Scene(BOX).aovs(**aovs)["normal"], chosen.aovs(**aovs)["normal"]))
        with self.assertRaises(ValueError):
            latentpt.Scene(BOX, sampler="halton")
        with self.assertRaises(ValueError):
            sobol.sampler = "halton"

    def test_a_fit_keeps_its_sampler_for_what_renders_it_later(self):
        small = dict(note=lambda t: None, synthetic_res="8x8", iterations=4, spp=2, final_spp=4, refiner=False)
        depth = {"integrator.max_depth": "3"}
        with tempfile.TemporaryDirectory() as d:
            chosen, by_file, sobol = (os.path.join(d, n) for n in ("chosen", "by_file", "sobol"))
            latentpt.fit(BOX, chosen, defines=depth, sampler="independent", **small)
            latentpt.fit(BOX, by_file, defines={**depth, **self.INDEPENDENT}, **small)
            latentpt.fit(BOX, sobol, defines=depth, **small)
            def params(fit):
                with open(os.path.join(fit, "params.json")) as f:
                    return f.read()
            self.assertEqual(params(chosen), params(by_file))
            self.assertNotEqual(params(chosen), params(sobol))
            with open(os.path.join(chosen, "fit.json")) as f:
                self.assertEqual(json.load(f)["sampler"], "independent")
            self.assertEqual(latentpt.LatentScene.from_fit(chosen).scene.sampler, "independent")
            self.assertEqual(latentpt.LatentScene.from_fit(chosen, sampler="sobol").scene.sampler, "sobol")
            edits = os.path.join(SRC, "scenes", "cornell-box", "edits-demo.json")
            frame = lambda **kw: latentpt.EditSession(sobol, edits, **kw).frame(3, spp=2)["latent"]  # noqa: E731
            np.testing.assert_array_equal(frame(sampler="independent"), frame(defines=self.INDEPENDENT))
            self.assertFalse(np.array_equal(frame(), frame(defines=self.INDEPENDENT)))


class OneProcessTest(unittest.TestCase):
    def test_refine_takes_the_command_lines_options(self):
        """refine(**options) trains as `latentpt refine --options` does: the same refiner.pt, byte for
        byte. An unknown option is a TypeError, a value out of its range a ValueError naming it."""
        with tempfile.TemporaryDirectory() as d:
            fit = os.path.join(d, "fit")
            latentpt.fit(BOX, fit, defines={"integrator.max_depth": "3"}, note=lambda t: None,
                         synthetic_res="8x8", iterations=4, spp=2, final_spp=4, refiner=False)
            cli = os.path.join(d, "cli")
            shutil.copytree(fit, cli)
            latentpt.refine(fit, note=lambda t: None, iterations=7, crop=6, lr=2e-3, lr_decay="cosine",
                            dropout=0.0, expansion=2, patience=0, seed=5, arch="unet", inputs="terms")
            with open(os.path.join(fit, "refiner_loss.csv")) as f:
                self.assertEqual(len(f.readlines()), 1 + 7)
            binary = os.environ.get("LATENTPT_BIN")
            if binary:
                subprocess.run([binary, "refine", cli, "-q", "--iterations", "7", "--crop", "6", "--lr", "0.002",
                                "--lr-decay", "cosine", "--dropout", "0", "--expansion", "2", "--patience", "0",
                                "--seed", "5", "--arch", "unet", "--inputs", "terms"],
                               check=True, stdout=subprocess.DEVNULL)
                with open(os.path.join(fit, "refiner.pt"), "rb") as a, open(os.path.join(cli, "refiner.pt"), "rb") as b:
                    self.assertEqual(a.read(), b.read())
            # emitters=True: the emitter refiner beside it (reading what it reads), the record added
            latentpt.refine(fit, note=lambda t: None, iterations=2, expansion=1, inputs="terms", emitters=True)
            self.assertTrue(os.path.exists(os.path.join(fit, "refiner_emitters.pt")))
            with open(os.path.join(fit, "metrics.json")) as f:
                self.assertEqual(json.load(f)["emitter_refiner"]["iterations"], 2)
            with self.assertRaises(TypeError):
                latentpt.refine(fit, crops=4)
            for bad, name in (({"dropout": 1.5}, "dropout"), ({"lr_decay": "linear"}, "lr_decay"),
                              ({"iterations": 0}, "iterations"), ({"augment": "turn"}, "turn"),
                              ({"arch": "mlp"}, "arch"), ({"inputs": "rgb"}, "inputs"),
                              ({"latent_target": "decoded"}, "latent_target"),
                              ({"latent_target_block": 16}, "latent-target-block"),
                              ({"window_stride": 0}, "window-stride"),
                              ({"input_noise": 0.1, "inputs": "terms"}, "input-noise")):
                with self.assertRaises(ValueError) as e:
                    latentpt.refine(fit, note=lambda t: None, **bad)
                self.assertIn(name, str(e.exception))
            with self.assertRaises(ValueError) as e:  # named as fit() spells it
                latentpt.fit(BOX, os.path.join(d, "fit2"), synthetic_res="8x8", refiner_norm="batch")
            self.assertIn("refiner_norm", str(e.exception))
            with self.assertRaises(ValueError) as e:  # fit() checks its refiner options before it starts
                latentpt.fit(BOX, os.path.join(d, "fit2"), synthetic_res="8x8", refiner_dropout=2.0)
            self.assertIn("dropout", str(e.exception))
            self.assertFalse(os.path.exists(os.path.join(d, "fit2")))

    def test_torch_and_latentpt_load_together_in_either_order(self):
        torch_or_skip()
        for first, second in (("torch", "latentpt"), ("latentpt", "torch")):
            code = (f"import {first}, {second}, latentpt.torch, numpy, torch; "
                    "s = latentpt.Scene(sys.argv[1]); print(float(s.render(spp=1, width=8, height=8).mean()))")
            r = subprocess.run([sys.executable, "-c", "import sys; " + code, BOX], capture_output=True, text=True,
                               env=os.environ.copy())
            self.assertEqual(r.returncode, 0, f"import {first} then {second}: {r.stderr}")
            self.assertGreater(float(r.stdout.strip()), 0.0)


if __name__ == "__main__":
    unittest.main()
