#!/usr/bin/env python3
"""Writes a closed-box white furnace as a Mitsuba 3 scene: a cube [-1, 1]^3 of n x n quads per face
(2 n^2 triangles), wound so that its normals face inward, every face a one-sided area emitter of
radiance Le inside a twosided diffuse of reflectance rho, and a camera inside. Every pixel's
expected value is Le / (1 - rho) exactly (10 for the defaults), whatever the renderer, so a
renderer's mean against that number is its bias on long diffuse paths (docs/validation.md,
"A furnace"). Python standard library only.

    python3 tools/furnace_box.py --out /tmp/furnace --n 1      # then render out/furnace.xml
"""
import argparse
import os


def box_obj(n):
    """OBJ text of the cube with n x n quads (two triangles each) per face, normals inward."""
    verts, faces = [], []
    for axis in range(3):
        for side in (1, -1):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            base = len(verts)
            for i in range(n + 1):
                for j in range(n + 1):
                    p = [0.0, 0.0, 0.0]
                    p[axis], p[u], p[v] = side, -1 + 2 * i / n, -1 + 2 * j / n
                    verts.append(p)
            for i in range(n):
                for j in range(n):
                    a = base + i * (n + 1) + j
                    b, c, d = a + n + 1, a + n + 2, a + 1
                    # (u x v) points along +axis; inward is -side * axis
                    tris = [(a, c, b), (a, d, c)] if side > 0 else [(a, b, c), (a, c, d)]
                    faces += tris
    lines = ["v %.6f %.6f %.6f" % tuple(p) for p in verts]
    lines += ["f %d %d %d" % (t[0] + 1, t[1] + 1, t[2] + 1) for t in faces]
    return "\n".join(lines) + "\n"


SCENE = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="{depth}"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="90"/>
    <transform name="to_world"><lookat origin="0.1, 0.2, 0.3" target="0.5, 0.1, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/><rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
  </sensor>
  <shape type="obj">
    <string name="filename" value="box.obj"/>
    <boolean name="face_normals" value="true"/>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="{rho}"/></bsdf></bsdf>
    <emitter type="area"><rgb name="radiance" value="{le}"/></emitter>
  </shape>
</scene>
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="folder for furnace.xml and box.obj")
    ap.add_argument("--n", type=int, default=1, help="quads per face side (1: 12 triangles)")
    ap.add_argument("--rho", type=float, default=0.9, help="diffuse reflectance, < 1")
    ap.add_argument("--le", type=float, default=1.0, help="emitted radiance")
    ap.add_argument("--max-depth", type=int, default=400, help="Mitsuba max_depth (rho^depth must be negligible)")
    a = ap.parse_args()
    if not (0.0 <= a.rho < 1.0) or a.n < 1:
        ap.error("need 0 <= --rho < 1 and --n >= 1")
    os.makedirs(a.out, exist_ok=True)
    for name, text in (("box.obj", box_obj(a.n)),
                       ("furnace.xml", SCENE.format(depth=a.max_depth, rho=a.rho, le=a.le))):
        tmp = os.path.join(a.out, name + ".tmp")
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, os.path.join(a.out, name))
    print("furnace_box: %s, expected pixel value %.6g" % (os.path.join(a.out, "furnace.xml"), a.le / (1.0 - a.rho)))


if __name__ == "__main__":
    main()
