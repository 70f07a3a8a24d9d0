#!/usr/bin/env python3
"""tools/coplanar_faces.py on a scene whose overlaps are known in closed form: unit squares in
the plane z = 0, one shifted by half its width (shared area 0.5, same facing), one edge-adjacent
(shared area 0), one lifted by 1e-3 (not coplanar) and one facing down through its to_world
(back to back, shared area 1); --push then resolves the same-facing overlap."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import coplanar_faces as C  # noqa: E402

TOOL = os.path.join(ROOT, "tools", "coplanar_faces.py")


def square(x0, z, up=True):
    """OBJ text of the square [x0, x0 + 1] x [0, 1] at height z, as two triangles facing +z (up)."""
    v = "v %g 0 %g\nv %g 0 %g\nv %g 1 %g\nv %g 1 %g\n" % (x0, z, x0 + 1, z, x0 + 1, z, x0, z)
    return v + ("f 1 2 3\nf 1 3 4\n" if up else "f 1 3 2\nf 1 4 3\n")


SHAPE = """  <shape type="obj" id="{id}"><string name="filename" value="{id}.obj"/>{extra}
    <bsdf type="diffuse"/></shape>
"""


def write_scene(folder, extra_e='<transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 -5 0 0 0 1"/></transform>'):
    objs = {"a": square(0, 0), "b": square(0.5, 0), "c": square(1, 0), "d": square(0, 1e-3), "e": square(0, 5, up=False)}
    for name, text in objs.items():
        with open(os.path.join(folder, name + ".obj"), "w") as f:
            f.write(text)
    shapes = "".join(SHAPE.format(id=n, extra=extra_e if n == "e" else "") for n in objs)
    path = os.path.join(folder, "scene.xml")
    with open(path, "w") as f:
        f.write('<scene version="3.0.0">\n' + shapes + "  <shape type=\"sphere\"/>\n</scene>\n")
    return path


def shared_area(meshes, found):
    """{(same_facing, shape, shape): summed area}."""
    out = {}
    for a, same, t, s in found:
        key = (same,) + tuple(sorted((meshes[t[0]][0], meshes[s[0]][0])))
        out[key] = out.get(key, 0.0) + a
    return out


class CoplanarFaces(unittest.TestCase):
    def test_shared_areas_in_closed_form(self):
        with tempfile.TemporaryDirectory() as tmp:
            meshes = C.scene_meshes(write_scene(tmp))
            areas = shared_area(meshes, C.overlaps(meshes))
        self.assertEqual(set(areas), {(True, "a", "b"), (True, "b", "c"), (False, "a", "e"), (False, "b", "e")})
        self.assertAlmostEqual(areas[(True, "a", "b")], 0.5, places=9)
        self.assertAlmostEqual(areas[(True, "b", "c")], 0.5, places=9)
        self.assertAlmostEqual(areas[(False, "a", "e")], 1.0, places=9, msg="to_world moves e onto a, facing down")
        self.assertAlmostEqual(areas[(False, "b", "e")], 0.5, places=9)

    def test_translate_and_scale_compose_like_a_matrix(self):
        with tempfile.TemporaryDirectory() as tmp:
            meshes = C.scene_meshes(write_scene(tmp, '<transform name="to_world"><scale value="2"/><translate z="-10"/></transform>'))
            areas = shared_area(meshes, C.overlaps(meshes))
        self.assertAlmostEqual(areas[(False, "a", "e")], 1.0, places=9, msg="scale 2 then translate: e covers a")

    def test_push_resolves_the_overlap(self):
        with tempfile.TemporaryDirectory() as tmp:
            folder = os.path.join(tmp, "scene")
            os.makedirs(folder)
            scene = write_scene(folder)
            with open(os.path.join(folder, "b.obj")) as f:
                original = f.read()
            out = os.path.join(tmp, "pushed")
            r = subprocess.run([sys.executable, TOOL, scene, "--push", "b:5,6", "--distance", "0.01", "--out", out],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertTrue(os.path.islink(os.path.join(out, "a.obj")))
            meshes = C.scene_meshes(os.path.join(out, "scene.xml"))
            b = next(m for m in meshes if m[0] == "b")
            self.assertTrue(all(abs(p[2] + 0.01) < 1e-9 for p in b[2]), "b moved back, along -z")
            areas = shared_area(meshes, C.overlaps(meshes))
            self.assertEqual(set(areas), {(False, "a", "e")})
            with open(os.path.join(folder, "b.obj")) as f:
                self.assertEqual(f.read(), original, "the scene's own OBJ is never written")

    def test_push_refuses_what_would_write_into_the_scene(self):
        with tempfile.TemporaryDirectory() as tmp:
            scene = write_scene(tmp)
            for out, why in ((tmp, "must not be the scene's folder"), (os.path.join(tmp, "sub"), "or inside it")):
                r = subprocess.run([sys.executable, TOOL, scene, "--push", "b:5,6", "--out", out],
                                   capture_output=True, text=True)
                self.assertEqual(r.returncode, 2)
                self.assertIn(why, r.stderr)
            r = subprocess.run([sys.executable, TOOL, scene, "--push", "b:5,9", "--out", os.path.join(tmp, "o")],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("no face on line(s) [9]", r.stderr)

    def test_push_refuses_faces_sharing_vertices_with_others(self):
        with tempfile.TemporaryDirectory() as tmp:
            r = subprocess.run([sys.executable, TOOL, write_scene(tmp), "--push", "b:5", "--out", os.path.join(tmp, "o")],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("also used by f-lines [6]", r.stderr)

    def test_a_transform_it_cannot_read_skips_that_shape_and_says_so(self):
        with tempfile.TemporaryDirectory() as tmp:
            scene = write_scene(tmp, '<transform name="to_world"><rotate x="1" angle="180"/></transform>')
            r = subprocess.run([sys.executable, TOOL, scene], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("shape 'e' skipped", r.stderr)
            self.assertIn("4 obj shapes", r.stdout)

    def test_bad_obj_is_one_clear_error(self):
        with tempfile.TemporaryDirectory() as tmp:
            scene = write_scene(tmp)
            for text, field in (("v 0 0 x\n", "field v"), ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "outside 1..3"),
                                ("v 0 0 0\nf 0 1 1\n", "outside 1..1"), ("v 0 0 0\nf 1 1\n", "at least 3")):
                with open(os.path.join(tmp, "c.obj"), "w") as f:
                    f.write(text)
                r = subprocess.run([sys.executable, TOOL, scene], capture_output=True, text=True)
                self.assertEqual(r.returncode, 2, text)
                self.assertIn("c.obj:", r.stderr)
                self.assertIn(field, r.stderr)
                self.assertNotIn("Traceback", r.stderr)
            os.remove(os.path.join(tmp, "c.obj"))
            r = subprocess.run([sys.executable, TOOL, scene], capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("c.obj", r.stderr)


if __name__ == "__main__":
    unittest.main()
