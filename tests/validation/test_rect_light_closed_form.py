#!/usr/bin/env python3
"""tools/rect_light_closed_form.py: Lambert's polygon formula against an independent closed form
(a point on the axis of a parallel rectangle, from the corner form factor) and against a seeded
Monte Carlo integral at an oblique point; zero behind the one-sided emitter; and, with the
latentpt binary and ../shared, the whole chain (XML, camera, receiver, box filter) on the Cornell
box's back wall at max_depth 2, where our render must equal the closed form within its noise."""
import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import rect_light_closed_form as rl  # noqa: E402

BIN = os.environ.get("LATENTPT_BIN")
SHARED = os.environ.get("LATENTPT_SHARED", os.path.join(ROOT, "..", "shared"))


def light(a, b, centre, rot=np.eye(3)):
    """A rectangle of half-sides a, b, emitting along rot's local +z."""
    m = np.eye(4)
    m[:3, :3] = rot @ np.diag([a, b, 1.0])
    m[:3, 3] = centre
    return {"light": m}


def corner_form_factor(x, y):
    """Form factor from a point below a rectangle's corner, planes parallel, sides x and y in units
    of the distance (the textbook formula, independent of the polygon one)."""
    sx, sy = math.sqrt(1 + x * x), math.sqrt(1 + y * y)
    return (x / sx * math.atan(y / sx) + y / sy * math.atan(x / sy)) / (2 * math.pi)


def rot_x(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


class Formula(unittest.TestCase):
    def test_on_axis_equals_corner_form_factor(self):
        # Light in the plane z = h, emitting down (rotated 180 degrees about x); point at the origin.
        for a, b, h in [(1.0, 1.0, 1.0), (0.3, 0.7, 2.0), (2.0, 0.1, 0.5)]:
            scene = light(a, b, [0, 0, h], rot_x(180))
            got = rl.polygon_irradiance_factor(scene, np.zeros((1, 3)), np.array([0, 0, 1.0]))[0]
            want = math.pi * 4 * corner_form_factor(a / h, b / h)  # E / L = pi F
            self.assertAlmostEqual(got / want, 1.0, delta=1e-9, msg=f"a {a} b {b} h {h}")

    def test_oblique_point_equals_monte_carlo(self):
        scene = light(0.4, 0.25, [0.3, -0.2, 1.1], rot_x(160))
        p, n = np.array([0.1, 0.5, 0.0]), np.array([0.0, 0.6, 0.8])
        got = rl.polygon_irradiance_factor(scene, p[None], n)[0]
        m = scene["light"]
        rng = np.random.default_rng(7)
        uv = rng.uniform(-1, 1, (2_000_000, 2))
        q = uv @ m[:3, :2].T + m[:3, 3]
        nl = m[:3, 2] / np.linalg.norm(m[:3, 2])
        d = q - p
        r2 = np.sum(d * d, -1)
        w = d / np.sqrt(r2)[:, None]
        cos_r, cos_l = np.clip(w @ n, 0, None), np.clip(-(w @ nl), 0, None)
        area = 4 * np.linalg.norm(np.cross(m[:3, 0], m[:3, 1]))
        samples = cos_r * cos_l / r2 * area
        mc, se = samples.mean(), samples.std() / math.sqrt(len(samples))
        self.assertLess(abs(got - mc), 4 * se + 1e-12, msg=f"closed form {got}, Monte Carlo {mc} +- {se}")

    def test_zero_behind_the_emitter(self):
        scene = light(0.5, 0.5, [0, 0, 1.0], rot_x(180))  # emits towards -z
        above = rl.polygon_irradiance_factor(scene, np.array([[0, 0, 2.0]]), np.array([0, 0, -1.0]))
        self.assertEqual(above[0], 0.0)


class Camera(unittest.TestCase):
    def test_image_axes_follow_mitsuba(self):
        # Identity to_world, 90 degrees: the camera looks down +z, image +x runs towards local -x
        # and image +y downwards, so the top-left pixel of a 2 x 2 image looks at (+0.5, +0.5, 1).
        scene = {"camera": np.eye(4), "fov": 90.0}
        _, d = rl.camera_rays(scene, 2, (0, 1), (0, 1), 1)
        np.testing.assert_allclose(d[0, 0, 0, 0], [0.5, 0.5, 1.0], atol=1e-12)

    def test_left_of_the_cornell_box_is_its_left_wall(self):
        # A mirrored image would put the left wall (x = -1) on the right; the box is symmetric
        # enough that the back wall's closed form could not tell.
        xml = os.path.join(SHARED, "scenes", "cornell-box", "scene_v3.xml")
        if not os.path.exists(xml):
            self.skipTest("no ../shared Cornell box")
        scene = rl.load_scene(xml, "Light", "LeftWall")
        origin, d = rl.camera_rays(scene, 64, (28, 36), (0, 4), 2)
        _, _, inside = rl.receiver_points(scene, origin, d)
        self.assertTrue(inside.all())
        self.assertTrue((d[..., 0] < 0).all())

    def test_sides_are_checked(self):
        wall = np.eye(4)  # the plane z = 0, normal +z
        scene = {"receiver": wall, "light": light(0.5, 0.5, [0, 0, 1.0], rot_x(180))["light"], "twosided": False}
        self.assertIsNone(rl.check_sides(scene, np.array([0, 0, 5.0])))
        self.assertIn("back of the one-sided", rl.check_sides(scene, np.array([0, 0, -5.0])))
        scene["twosided"] = True
        self.assertIn("camera's side", rl.check_sides(scene, np.array([0, 0, -5.0])))


class CornellBackWall(unittest.TestCase):
    def test_ours_equals_closed_form(self):
        scene = os.path.join(SHARED, "scenes", "cornell-box", "scene_v3.xml")
        if BIN is None or not os.path.exists(scene):
            self.skipTest("no latentpt binary (LATENTPT_BIN) or no ../shared Cornell box")
        with tempfile.TemporaryDirectory() as tmp:
            outs = []
            for seed in (1, 2):
                out = os.path.join(tmp, f"ours_{seed}.exr")
                subprocess.run([BIN, "render", scene, "--res", "64x64", "--spp", "256", "--seed", str(seed),
                                "-D", "max_depth=2", "-q", "--out", out], check=True)
                outs.append(out)
            tool = os.path.join(ROOT, "tools", "rect_light_closed_form.py")
            # Rows 10..23 of 64: the back wall below the light's plane (row 8.6), above the boxes;
            # away from the edges, where the image is smooth and the scene's tent filter is close
            # to the box filter assumed here.
            res = subprocess.run([sys.executable, tool, scene, "--emitter", "Light", "--receiver", "BackWall",
                                  "--rows", "10:24", "--cols", "10:54", "--res", "64", "--band", "14",
                                  "ours=" + ",".join(outs)], capture_output=True, text=True)
            self.assertEqual(res.returncode, 0, res.stderr)
            line = next(l for l in res.stdout.splitlines() if "whole region" in l)
            ratios = [float(v) for v in line.split(":")[-1].split()[-3:]]
            for r in ratios:  # 2 x 256 spp over 616 pixels: noise ~0.05 %
                self.assertAlmostEqual(r, 1.0, delta=3e-3, msg=line)
            # A region that does not see the receiver is refused with exit status 2.
            bad = subprocess.run([sys.executable, tool, scene, "--emitter", "Light", "--receiver", "BackWall",
                                  "--rows", "0:8", "--cols", "0:8", "--res", "64", "ours=" + outs[0]],
                                 capture_output=True, text=True)
            self.assertEqual(bad.returncode, 2, bad.stdout + bad.stderr)
            self.assertIn("does not see 'BackWall'", bad.stderr)


if __name__ == "__main__":
    unittest.main()
