#!/usr/bin/env python3
"""Finds triangles of a Mitsuba 3 scene's OBJ meshes that lie in one plane and overlap
(docs/validation.md, "classroom's window blocks"). Python standard library only.

Two faces on top of each other facing the same way are a scene defect that renderers resolve
differently: one that starts a ray on the surface and skips only the triangle it leaves (Cycles
3.x) hits the coplanar twin at distance ~0, so paths and shadow rays from there are trapped and the
patch renders black; one that offsets ray origins along the normal (Mitsuba, Tungsten, latentpt)
steps over it. Faces overlapping back to back (a box resting on the floor) are usually harmless.

    python3 tools/coplanar_faces.py ../shared/scenes/classroom/scene_constant.xml
    python3 tools/coplanar_faces.py SCENE.xml --push Walls_0005:2004,2005 --distance 0.001 --out DIR

--push writes a copy of the scene's folder to DIR (links to every file, the one OBJ rewritten)
with the listed faces (OBJ line numbers, as the report prints them) moved back along their normal
by --distance: a render of the difference that resolves the overlap without changing what is seen.
Exit status 2 with one message naming the file and field for input this script cannot read.
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

import mitsuba_transform


def fail(msg):
    print("coplanar_faces: " + msg, file=sys.stderr)
    sys.exit(2)


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def obj_index(token, count, where):
    """0-based vertex index of an OBJ face token ('7', '7/1/2', '-1') among count vertices so far."""
    try:
        i = int(token.split("/")[0])
    except ValueError:
        fail("%s: field f: '%s' is not a vertex index" % (where, token))
    if not (1 <= i <= count or -count <= i <= -1):
        fail("%s: field f: vertex index %d outside 1..%d (or -%d..-1)" % (where, i, count, count))
    return i - 1 if i > 0 else count + i


def read_obj(path):
    """Vertex positions and triangles (fan-triangulated), each triangle with its 'f' line number."""
    verts, tris = [], []
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError as e:
        fail("%s: %s" % (path, e.strerror or e))
    for number, line in enumerate(lines, 1):
        parts = line.split()
        where = "%s:%d" % (path, number)
        if parts and parts[0] == "v":
            try:
                verts.append(tuple(float(x) for x in parts[1:4]))
            except ValueError:
                fail("%s: field v: '%s' is not three numbers" % (where, " ".join(parts[1:4])))
            if len(verts[-1]) != 3:
                fail("%s: field v: needs x y z" % where)
        elif parts and parts[0] == "f":
            if len(parts) < 4:
                fail("%s: field f: a face needs at least 3 vertices" % where)
            idx = [obj_index(t, len(verts), where) for t in parts[1:]]
            tris += [((idx[0], idx[k], idx[k + 1]), number) for k in range(1, len(idx) - 1)]
    return verts, tris


def to_world(shape, xml_path):
    """The shape's 4x4 to_world (identity without one), or None when it uses a transform this
    script does not read (rotate, lookat): the caller skips that shape and says so."""
    try:
        return mitsuba_transform.to_world(shape, "%s: shape '%s'" % (xml_path, shape.get("id")))
    except ValueError as e:
        fail(str(e))


def scene_meshes(xml_path):
    """(shape id, OBJ path, world-space vertices, triangles, to_world) of every obj shape."""
    try:
        root = ET.parse(xml_path).getroot()
    except (OSError, ET.ParseError) as e:
        fail("%s: %s" % (xml_path, e))
    meshes = []
    for n, shape in enumerate(root.iter("shape")):
        if shape.get("type") != "obj":
            continue
        name = shape.find("string[@name='filename']")
        if name is None:
            fail("%s: shape '%s': field filename is missing" % (xml_path, shape.get("id")))
        path = os.path.join(os.path.dirname(xml_path), name.get("value"))
        M = to_world(shape, xml_path)
        if M is None:
            print("coplanar_faces: %s: shape '%s' skipped: its to_world uses a transform other than matrix, "
                  "translate or scale" % (xml_path, shape.get("id")), file=sys.stderr)
            continue
        verts, tris = read_obj(path)
        world = [tuple(sum(M[r][c] * p[c] for c in range(3)) + M[r][3] for r in range(3)) for p in verts]
        meshes.append((shape.get("id") or "shape%d" % n, path, world, tris, M))
    return meshes


def clip(poly, a, b):
    """The part of a convex 2D polygon left of the directed line a -> b (Sutherland-Hodgman)."""
    def side(p):
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    out = []
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        sp, sq = side(p), side(q)
        if sp >= 0:
            out.append(p)
        if (sp >= 0) != (sq >= 0):
            t = sp / (sp - sq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def area2d(poly):
    return 0.5 * sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(poly, poly[1:] + poly[:1]))


def ccw(t):
    return t if area2d(list(t)) >= 0 else (t[0], t[2], t[1])


def overlap_area(t, u):
    """Area shared by two 2D triangles."""
    poly, t = list(ccw(u)), ccw(t)
    for k in range(3):
        poly = clip(poly, t[k], t[(k + 1) % 3])
        if len(poly) < 3:
            return 0.0
    return abs(area2d(poly))


def planes(meshes, tol):
    """Triangles grouped by their plane: normal up to sign (to 1e-3), then runs of offsets that
    are each within tol of the one before. A lint, not a proof: two normals on either side of a
    1e-3 rounding boundary land in different groups, and such a pair is missed."""
    by_normal = {}
    for m, (_, _, world, tris, _) in enumerate(meshes):
        for k, ((i, j, l), line) in enumerate(tris):
            a, b, c = world[i], world[j], world[l]
            n = cross(sub(b, a), sub(c, a))
            length = math.sqrt(dot(n, n))
            if length < 1e-12:
                continue
            n = tuple(x / length for x in n)
            s = 1.0 if next(x for x in n if abs(x) > 1e-4) > 0 else -1.0  # stable at 45 degrees
            key = tuple(round(s * x / 1e-3) for x in n)
            by_normal.setdefault(key, []).append((s * dot(n, a), (m, k, line, n, (a, b, c))))
    groups = []
    for items in by_normal.values():
        items.sort(key=lambda it: it[0])
        start = 0
        for i in range(1, len(items) + 1):
            if i == len(items) or items[i][0] - items[i - 1][0] > tol:
                groups.append([it[1] for it in items[start:i]])
                start = i
    return groups


def overlaps(meshes, tol=1e-5, min_area=1e-8):
    """Pairs of coplanar triangles sharing an area > min_area: (area, same_facing, tri, tri)."""
    found = []
    for group in planes(meshes, tol):
        if len(group) < 2:
            continue
        n = group[0][3]
        u = cross(n, (1.0, 0.0, 0.0) if abs(n[0]) < 0.9 else (0.0, 1.0, 0.0))
        u = tuple(x / math.sqrt(dot(u, u)) for x in u)
        v = cross(n, u)
        flat = [tuple((dot(p, u), dot(p, v)) for p in g[4]) for g in group]
        order = sorted(range(len(group)), key=lambda i: min(p[0] for p in flat[i]))
        for x, i in enumerate(order):
            hi = max(p[0] for p in flat[i])
            for j in order[x + 1:]:
                if min(p[0] for p in flat[j]) >= hi:
                    break
                a = overlap_area(flat[i], flat[j])
                if a > min_area:
                    found.append((a, dot(group[i][3], group[j][3]) > 0, group[i], group[j]))
    return found


def centre(tri):
    return tuple(round(sum(p[c] for p in tri[4]) / 3, 4) for c in range(3))


def report(meshes, found, every=False):
    """One line per pair of shapes (same-facing first, by shared area), or with every=True one per
    pair of triangles."""
    if every:
        return ["%s %.4g: %s f-line %d, %s f-line %d, near %s" % (
            "SAME-FACING" if same else "back-to-back", a, meshes[t[0]][0], t[2], meshes[s[0]][0], s[2], centre(t))
            for a, same, t, s in sorted(found, key=lambda f: (not f[1], -f[0]))]
    by_pair = {}
    for a, same, t, s in found:
        key = (same,) + tuple(sorted((meshes[t[0]][0], meshes[s[0]][0])))
        by_pair.setdefault(key, []).append((a, t, s))
    lines = []
    for (same, one, two), items in sorted(by_pair.items(), key=lambda kv: (not kv[0][0], -sum(i[0] for i in kv[1]))):
        a, t, s = max(items, key=lambda i: i[0])
        lines.append("%s %s / %s: %d pair(s), %.4g area; largest %.4g: %s f-line %d and %s f-line %d near %s" % (
            "SAME-FACING" if same else "back-to-back", one, two, len(items), sum(i[0] for i in items), a,
            meshes[t[0]][0], t[2], meshes[s[0]][0], s[2], centre(t)))
    return lines


def parse_push(spec, meshes, xml_path):
    """The mesh and the OBJ f-line numbers that --push SHAPE:LINE,LINE names; each must exist."""
    shape_id, _, numbers = spec.partition(":")
    try:
        wanted = {int(x) for x in numbers.split(",") if x}
    except ValueError:
        fail("--push %s: expected SHAPE_ID:LINE,LINE (OBJ f-line numbers)" % spec)
    mesh = next((m for m in meshes if m[0] == shape_id), None)
    if mesh is None or not wanted:
        fail("--push %s: expected SHAPE_ID:LINE,LINE with an obj shape of %s" % (spec, xml_path))
    missing = sorted(wanted - {line for _, line in mesh[3]})
    if missing:
        fail("--push %s: %s has no face on line(s) %s" % (spec, mesh[1], missing[:8]))
    if any(abs(mesh[4][r][c] - (r == c)) > 1e-12 for r in range(4) for c in range(4)):
        fail("--push %s: shape '%s' has a to_world; only untransformed shapes can be pushed (the "
             "distance and the side are the OBJ's own)" % (spec, shape_id))
    return mesh, wanted


def copy_target(xml_path, obj_path, out):
    """(scene folder, where the rewritten OBJ goes): refuses an --out that is or lies inside the
    scene folder, and an OBJ outside it, so the original files are never written."""
    src = os.path.realpath(os.path.dirname(os.path.abspath(xml_path)))
    dst = os.path.realpath(out)
    obj = os.path.realpath(obj_path)
    if dst == src or dst.startswith(src + os.sep):
        fail("--out %s: must not be the scene's folder or inside it" % out)
    if not obj.startswith(src + os.sep):
        fail("--push: %s lies outside the scene's folder %s; copy the scene first" % (obj_path, src))
    return src, os.path.join(dst, os.path.relpath(obj, src))


def link_tree(src, dst, skip):
    """dst mirrors src: folders made, files and linked folders linked, skip (a real path) left out."""
    for folder, dirs, files in os.walk(src):
        target = os.path.join(dst, os.path.relpath(folder, src))
        os.makedirs(target, exist_ok=True)
        linked = [d for d in dirs if os.path.islink(os.path.join(folder, d))]
        for name in files + linked:
            here, link = os.path.join(folder, name), os.path.join(target, name)
            if os.path.realpath(here) != skip and not os.path.lexists(link):
                os.symlink(here, link)


def push(xml_path, meshes, spec, distance, out):
    """Writes the scene folder to out with spec's faces moved back by distance along their normal."""
    (_, path, verts, tris, _), wanted = parse_push(spec, meshes, xml_path)
    moved = {i for tri, line in tris if line in wanted for i in tri}
    shared = sorted(line for tri, line in tris if line not in wanted and moved & set(tri))
    if shared:
        fail("--push %s: its vertices are also used by f-lines %s of %s" % (spec, shared[:8], path))
    normals = []
    for tri, line in tris:
        if line in wanted:
            n = cross(sub(verts[tri[1]], verts[tri[0]]), sub(verts[tri[2]], verts[tri[0]]))
            normals.append(tuple(x / max(math.sqrt(dot(n, n)), 1e-30) for x in n))
    if any(dot(n, normals[0]) < 1 - 1e-6 for n in normals):
        fail("--push %s: the faces must share one normal (one side of one plane)" % spec)
    src, target = copy_target(xml_path, path, out)
    link_tree(src, os.path.realpath(out), os.path.realpath(path))
    rewritten, vertex = [], -1
    with open(path) as f:
        for line in f:
            parts = line.split()
            if parts and parts[0] == "v":
                vertex += 1
                if vertex in moved:
                    p = [float(x) - distance * normals[0][c] for c, x in enumerate(parts[1:4])]
                    line = " ".join(["v"] + ["%.9g" % x for x in p] + parts[4:]) + "\n"
            rewritten.append(line)
    with open(target + ".tmp", "w") as f:
        f.writelines(rewritten)
    os.replace(target + ".tmp", target)  # replaces a link left by an earlier copy, never its file
    return os.path.join(out, os.path.basename(xml_path)), len(moved)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="Mitsuba 3 XML; its obj shapes are read with their to_world (matrix, translate, scale)")
    ap.add_argument("--tol", type=float, default=1e-5, help="plane offsets closer than this count as one plane")
    ap.add_argument("--push", metavar="SHAPE:LINES", help="faces (OBJ f-line numbers) to move back, e.g. Walls_0005:2004,2005")
    ap.add_argument("--every", action="store_true", help="one line per pair of triangles")
    ap.add_argument("--distance", type=float, default=1e-3, help="how far --push moves them")
    ap.add_argument("--out", help="with --push: folder for the scene copy")
    a = ap.parse_args()
    meshes = scene_meshes(a.scene)
    if a.push:
        if not a.out:
            ap.error("--push needs --out")
        scene, n = push(a.scene, meshes, a.push, a.distance, a.out)
        print("coplanar_faces: %s (%d vertices moved by %g)" % (scene, n, a.distance))
        return
    found = overlaps(meshes, a.tol)
    print("coplanar_faces: %s: %d obj shapes, %d triangles, %d overlapping coplanar pairs" % (
        a.scene, len(meshes), sum(len(m[3]) for m in meshes), len(found)))
    for line in report(meshes, found, a.every):
        print("  " + line)


if __name__ == "__main__":
    main()
