#!/usr/bin/env python3
"""tools/cycles_reference.py's emitting sphere (docs/validation.md, "dining-room's last offset"):
the UV polyhedron Blender renders has the true sphere's area (so a sphere light's power and far
irradiance are the sphere's), radial unit normals, and few enough triangles that Cycles 3.4 keeps
their emitted light (it lost 0.39 % of a 512 x 256 sphere light). Other spheres stay inscribed."""
import math
import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "tools"))
import cycles_reference as C  # noqa: E402  (bpy is None outside Blender)


class SphereTest(unittest.TestCase):
    def test_the_polyhedron_has_the_spheres_area_and_radial_normals(self):
        P, tris, normals, uv = C.make_sphere(C.EMITTER_SPHERE_SEGMENTS, match_area=True)
        p = P[tris]
        area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
        self.assertAlmostEqual(area / (4 * math.pi), 1.0, places=9)
        self.assertGreater(np.linalg.norm(P, axis=-1).min(), 1.0)  # inscribed: pushed out
        P0, _, _, _ = C.make_sphere()  # a sphere that emits nothing keeps its vertices on the sphere
        np.testing.assert_allclose(np.linalg.norm(P0, axis=-1), 1.0, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-12)
        radial = p / np.linalg.norm(p, axis=-1, keepdims=True)
        np.testing.assert_allclose(normals, radial, atol=1e-12)
        # every face points outwards (the winding Blender shades and emits by)
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        self.assertTrue((np.einsum("ij,ij->i", n, p.mean(axis=1)) > 0).all())

    def test_few_enough_triangles_for_cycles_sphere_lights(self):
        nu, nv = C.EMITTER_SPHERE_SEGMENTS
        self.assertLessEqual(2 * nu * nv, 2 * 128 * 64)


if __name__ == "__main__":
    unittest.main()
