#!/usr/bin/env python3
"""scripts/light_response.py slope: the regression of a folder's frame changes on its references'
changes, on flat pictures whose linear values are known (display value d ↦ d^2.2), and its
refusals of bad input (one message naming the file, exit 1, no traceback). ~20 s."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "scripts", "light_response.py")


def flat_png(path, byte, size=128):
    """A size² PNG whose three channels all hold the 8-bit display value `byte`."""
    v = byte / 255
    subprocess.run(["oiiotool", "--pattern", f"constant:color={v},{v},{v}", f"{size}x{size}", "3", "-d", "uint8",
                    "-o", path], check=True, capture_output=True)


def halves_png(path, left, right):
    """A 128 × 64 PNG: two 64-pixel blocks, grey `left` and `right` (8-bit display values)."""
    a, b = left / 255, right / 255
    subprocess.run(["oiiotool", "--pattern", f"constant:color={a},{a},{a}", "128x64", "3",
                    f"--fill:color={b},{b},{b}", "64x64+64+0", "-d", "uint8", "-o", path],
                   check=True, capture_output=True)


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


class Slope(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="light-response-")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def folder(self, frames, references, size=128):
        for i, byte in frames.items():
            flat_png(os.path.join(self.dir, f"frame_{i:04d}.png"), byte, size)
        for i, byte in references.items():
            flat_png(os.path.join(self.dir, f"frame_{i:04d}_reference.png"), byte, size)

    def slope(self, frame):
        r = run("slope", self.dir, "--frames", str(frame))
        self.assertEqual(r.returncode, 0, r.stderr)
        return float(r.stdout.split("slope")[-1])

    def test_the_slope_is_the_ratio_of_linear_changes(self):
        # dark values, where the power 2.2 and the sRGB curve part (the script used sRGB at first)
        self.folder({0: 5, 20: 20}, {0: 5, 20: 40})

        def ratio(linear):
            return (linear(20 / 255) - linear(5 / 255)) / (linear(40 / 255) - linear(5 / 255))

        measured = self.slope(20)
        self.assertAlmostEqual(measured, ratio(lambda d: d ** 2.2), places=3)
        srgb = ratio(lambda d: d / 12.92 if d <= 0.04045 else ((d + 0.055) / 1.055) ** 2.4)
        self.assertGreater(abs(measured - srgb), 0.05)
        self.assertGreater(abs(measured - ratio(lambda d: d)), 0.05)  # nor the display values

    def test_each_block_is_paired_with_its_own(self):
        # the references brighten the left block more, the frame the right one: blocks paired
        # wrongly (a transposed reshape, one mean over the picture) would give 1
        for name, left, right in (("frame_0000_reference", 5, 5), ("frame_0020_reference", 40, 20),
                                  ("frame_0000", 5, 5), ("frame_0020", 20, 40)):
            halves_png(os.path.join(self.dir, name + ".png"), left, right)
        a, b = ((40 / 255) ** 2.2 - (5 / 255) ** 2.2), ((20 / 255) ** 2.2 - (5 / 255) ** 2.2)
        self.assertAlmostEqual(self.slope(20), 2 * a * b / (a * a + b * b), places=3)

    def test_bad_folders_are_refused_by_name(self):
        cases = {
            "missing frame": ({0: 51}, {0: 51, 20: 102}, 128, "frame_0020.png: missing"),
            "no change": ({0: 51, 20: 77}, {0: 51, 20: 51}, 128, "true change is zero"),
            "too small": ({0: 51, 20: 77}, {0: 51, 20: 102}, 32, "smaller than one 64-pixel block"),
        }
        for name, (frames, references, size, message) in cases.items():
            with self.subTest(name):
                shutil.rmtree(self.dir)
                os.makedirs(self.dir)
                self.folder(frames, references, size)
                r = run("slope", self.dir, "--frames", "20")
                self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
                self.assertIn(message, r.stderr)
                self.assertNotIn("Traceback", r.stderr)

    def test_bad_scales_are_refused_before_any_work(self):
        for argv in (["exposure", self.dir, "--k", "1"], ["exposure", self.dir, "--k", "nan"],
                     ["black", "no-scene.xml", "--k", "-2"], ["black", "no-scene.xml", "--res", "100"]):
            with self.subTest(argv):
                r = run(*argv)
                self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
                self.assertIn("light_response.py: error:", r.stderr)
                self.assertNotIn("Traceback", r.stderr)


if __name__ == "__main__":
    if not shutil.which("oiiotool"):
        print("oiiotool not installed: skipped")
        sys.exit(77)
    unittest.main()
