#!/usr/bin/env python3
"""latentpt in a closed-box white furnace (tools/furnace_box.py): every pixel's expectation is
Le / (1 - rho) = 10, so the image mean must be 10 within its noise, for a box of 12 triangles and
one of 768, with both samplers. One 64² render at 256 spp has a standard error of ~0.04 %; the
tolerance is 0.25 %, far below what a lost bounce (10 %) or a leak along the edges would cost."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
BIN = os.environ.get("LATENTPT_BIN")  # ctest sets it to the built latentpt


def image_mean(path):
    """Mean of the first channel, from oiiotool --printstats."""
    out = subprocess.run(["oiiotool", path, "--printstats"], capture_output=True, text=True, check=True).stdout
    line = next(l for l in out.splitlines() if "Stats Avg:" in l)
    return float(line.split(":", 1)[1].split()[0])


class Furnace(unittest.TestCase):
    def test_mean_is_le_over_one_minus_rho(self):
        if BIN is None:
            self.skipTest("no latentpt binary (LATENTPT_BIN)")
        with tempfile.TemporaryDirectory() as tmp:
            for n in (1, 8):
                folder = os.path.join(tmp, "n%d" % n)
                subprocess.run([sys.executable, os.path.join(ROOT, "tools", "furnace_box.py"), "--out", folder,
                                "--n", str(n)], check=True, capture_output=True)
                for sampler in ("independent", "sobol"):
                    out = os.path.join(folder, sampler + ".exr")
                    subprocess.run([BIN, "--sampler", sampler, "render", os.path.join(folder, "furnace.xml"),
                                    "--spp", "256", "--seed", "3", "-q", "--out", out], check=True)
                    mean = image_mean(out)
                    self.assertAlmostEqual(mean / 10.0, 1.0, delta=2.5e-3, msg="n %d, %s: mean %.5f" % (n, sampler, mean))


if __name__ == "__main__":
    unittest.main()
