#!/usr/bin/env python3
"""scripts/validate_renderer.py's rewritten scene copies (docs/validation.md, "Splitting a
difference"): cycles_approximation lands on plastic, roughplastic and roughconductor and nowhere
else, face_normals and the box filter replace what was there, smooth conductors (and nothing else)
become diffuse, and latentpt loads every rewritten copy of a paper scene (when ../shared is
present)."""
import os
import re
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import validate_renderer as V  # noqa: E402

BIN = os.environ.get("LATENTPT_BIN")  # ctest sets it to the built latentpt

SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><rfilter type="tent"><float name="radius" value="2"/></rfilter></film></sensor>
  <!-- <bsdf type="roughconductor" id="old"/> <shape type="obj" id="old"><string name="filename" value="x.obj"/></shape> -->
  <!-- <bsdf type="conductor" id="old_mirror"/> -->
  <bsdf type="twosided" id="a"><bsdf type="roughplastic"><float name="alpha" value="0.1"/></bsdf></bsdf>
  <bsdf type="plastic" id="b"/>
  <bsdf type="roughconductor" id="c" ><float name="alpha" value="0.2"/></bsdf>
  <bsdf type="diffuse" id="d"/>
  <bsdf type="roughdielectric" id="e"/>
  <bsdf type="conductor" id="f"><rgb name="specular_reflectance" value="1.0"/></bsdf>
  <bsdf id="g" type="conductor"/>
  <bsdf type="twosided" id="h"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></bsdf>
  <shape type="obj" id="m1"><string name="filename" value="a.obj"/></shape>
  <shape type="ply" id="m2"><boolean value="false" name="face_normals"/><string name="filename" value="b.ply"/></shape>
  <shape type="rectangle" id="r"/>
</scene>
"""


def bsdf_with_flag(text):
    """Types of the <bsdf> elements whose first child is the cycles_approximation flag."""
    return re.findall(r'<bsdf type="(\w+)"[^>]*><boolean name="cycles_approximation" value="true"/>', text)


class Rewrites(unittest.TestCase):
    def test_approximation_flag_only_on_the_three_plugins(self):
        text, n = V.with_approximations(SCENE)
        self.assertEqual(n, 3)
        self.assertEqual(sorted(bsdf_with_flag(text)), ["plastic", "roughconductor", "roughplastic"])
        self.assertIn('<bsdf type="plastic" id="b"><boolean name="cycles_approximation" value="true"/></bsdf>', text)
        self.assertEqual(text.count("cycles_approximation"), 3)
        self.assertIn('<!-- <bsdf type="roughconductor" id="old"/>', text, "comments stay as they are")

    def test_face_normals_on_every_mesh_and_only_meshes(self):
        text, n = V.with_face_normals(SCENE)
        self.assertEqual(n, 2)
        self.assertEqual(text.count('name="face_normals" value="true"'), 2)
        self.assertEqual(text.count("face_normals"), 2, "one key per mesh, whatever the attribute order")
        self.assertNotIn('value="false"', text)
        self.assertIn('<shape type="rectangle" id="r"/>', text)

    def test_box_filter(self):
        text, n = V.with_box_filter(SCENE)
        self.assertEqual(n, 1)
        self.assertIn('<film type="hdrfilm"><rfilter type="box"/></film>', text, "the tent's radius goes too")

    def test_diffuse_mirrors_only_smooth_conductors(self):
        text, n = V.with_diffuse_mirrors(SCENE)
        self.assertEqual(n, 3)
        self.assertIn('<bsdf type="diffuse" id="f"><rgb name="reflectance" value="0.8"/></bsdf>', text)
        self.assertIn('<bsdf id="g" type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>', text)
        self.assertIn('<bsdf type="twosided" id="h"><bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></bsdf>',
                      text, "a nested conductor ends at its own </bsdf>")
        self.assertEqual(text.count('type="conductor"'), 1, "only the commented-out one is left")
        self.assertEqual(text.count('type="roughconductor"'), 2, "rough conductors and the comment stay")
        self.assertIn('<!-- <bsdf type="conductor" id="old_mirror"/> -->', text, "a commented-out mirror stays")
        self.assertNotIn("specular_reflectance", text)

    def test_paper_scenes_load_rewritten(self):
        shared = os.environ.get("LATENTPT_SHARED", os.path.join(ROOT, "..", "shared"))
        if BIN is None or not os.path.isdir(os.path.join(shared, "scenes")):
            self.skipTest("no latentpt binary or no ../shared scenes")
        with tempfile.TemporaryDirectory() as tmp:
            for name in ("dining-room", "classroom"):
                original = os.path.join(shared, "scenes", V.SCENES[name])
                path, changed = V.scene_variant(original, os.path.join(tmp, name), "all", approximate=True, flat=True,
                                                box=True)
                self.assertGreater(changed["bsdfs"], 0)
                self.assertGreater(changed["meshes"], 0)
                out = os.path.join(tmp, name + ".exr")
                r = subprocess.run([BIN, "render", path, "--res", "16x12", "--spp", "1", "-q", "--out", out],
                                   capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertTrue(os.path.exists(out))
            path, changed = V.scene_variant(os.path.join(shared, "scenes", "cbox", "cbox_specular.xml"),
                                            os.path.join(tmp, "cbox"), "mirrors", diffuse_mirrors=True)
            self.assertEqual(changed["mirrors"], 1, "cbox-specular has one mirror (and one commented out)")
            out = os.path.join(tmp, "cbox.exr")
            r = subprocess.run([BIN, "render", path, "--res", "16x12", "--spp", "1", "-q", "--out", out],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main()
