#!/usr/bin/env python3
"""Independent Cycles reference renders of latentpt's Mitsuba 3 XML scenes.

Runs inside Blender (Debian's blender 3.4.1; its Python has numpy). It translates the subset of
Mitsuba 3 XML used by ../shared/scenes (see the README there) into a Blender scene and renders it
with Cycles on the CPU, unbiased and without denoising, to a float32 linear RGB OpenEXR. It shares
no code with latentpt: it exists to check latentpt's renderer against a renderer written by others.

usage:
  blender -b --factory-startup --python tools/cycles_reference.py -- SCENE.xml --out ref.exr
        [--spp N] [--res WxH] [--seed S] [--threads T] [-D name=value ...] [--max-depth N]
        [--strategy mis|bsdf] [--no-roulette] [--pattern sobol|pmj]

  --out FILE        output EXR (float32 RGB, linear, no view transform). Written atomically
                    (rendered to NAME.tmp.exr beside it, then renamed), with a sidecar FILE.json:
                    the approximations made, the settings used, render time, Blender version.
  --spp N           samples per pixel (default: the XML's sampler sample_count)
  --res WxH         film size (default: the XML's film width/height)
  --seed S          Cycles seed (default 0)
  --threads T       CPU threads (default 2)
  -D name=value     override an XML <default name value> (repeatable; also -Dname=value)
  --max-depth N     Mitsuba max_depth of the path integrator (default: the XML's)
  --strategy S      mis (default): emitters and the environment are light-sampled as well as hit
                    by BSDF sampling, as Mitsuba's path integrator does; bsdf: no light sampling
                    (every material's "Multiple Importance" off, the world not sampled), so
                    emission counts only where a BSDF-sampled ray hits it (latentpt render
                    --strategy bsdf). Both estimate the same image, so a difference
                    between them is a bias in one of Cycles' two estimators.
  --no-roulette     no Russian roulette in Cycles (min_light_bounces above the bounce limit): every
                    path runs to max_depth. Slow; for checking Cycles' roulette, which loses
                    energy on long paths (docs/validation.md, "A furnace").
  --pattern P       Cycles' sampling pattern: sobol (default) or pmj (progressive multi-jittered,
                    Blender's default). With pmj, Cycles 3.4's direct light from a
                    16 k-triangle sphere light is biased at low sample counts, by up to ~0.7 %
                    of either sign with the geometry (dining-room: +0.65 % at 64-256 spp,
                    +0.2 % at 512, none at 1024-2048, against a closed form;
                    docs/validation.md, "dining-room's last offset"); sobol showed none. pmj
                    prints an APPROXIMATION.
  --help            this text

Exit status: 0 on success; 2 when the scene uses something this script cannot translate
faithfully (the message names the file, line and field); 3 on an internal error. Blender itself
would exit 0 after a failing --python script, so failures call os._exit() after flushing.

Every place where Cycles cannot express Mitsuba's model exactly is printed as a line starting
"APPROXIMATION:" and listed in the sidecar JSON. Nothing is silently substituted: an unknown
plugin, or a property that would change the image, is an error.

Conventions (Mitsuba 3 -> Blender/Cycles), worked out from both renderers' sources:
  * World coordinates are used as they are (no y-up/z-up swap): nothing in Cycles depends on
    which axis is up except the environment map lookup, which is mapped explicitly.
  * Geometry is baked into world space in Python (positions by to_world, normals by its inverse
    transpose, renormalised; winding reversed where det(to_world) < 0), and every object keeps an
    identity matrix: Blender decomposes object matrices into loc/rot/scale and would lose shear.
  * Camera: Mitsuba looks down +z with +y up and image +x towards camera -x; a Blender camera
    looks down -z with +y up and +x to the right. Blender matrix = to_world * diag(-1, 1, -1, 1).
  * max_depth: Mitsuba counts path segments (1: emitters seen directly, 2: direct lighting),
    Cycles counts bounces after the first hit, so max_bounces = max_depth - 2.
"""
import json
import math
import os
import re
import sys
import time
import traceback
import xml.parsers.expat

import numpy as np

try:
    import bpy
    from mathutils import Matrix
except ImportError:  # --help works outside Blender too
    bpy = None

USAGE = __doc__[__doc__.index("usage:"):__doc__.index("Exit status:")].rstrip() + "\n"


# --------------------------------------------------------------------------------------------
# Reporting
# --------------------------------------------------------------------------------------------

class SceneError(Exception):
    """Something in the scene this script cannot translate faithfully."""

    def __init__(self, msg, file=None, line=None, field=None):
        super().__init__(msg)
        self.msg, self.file, self.line, self.field = msg, file, line, field

    def __str__(self):
        where = self.file or "<scene>"
        if self.line:
            where += ":%d" % self.line
        if self.field:
            where += ": field '%s'" % self.field
        return "%s: %s" % (where, self.msg)


APPROXIMATIONS = []  # what Cycles renders differently from Mitsuba (each printed once)
SAMPLING_PATTERNS = {"sobol": "SOBOL", "pmj": "PROGRESSIVE_MULTI_JITTER"}  # --pattern -> Cycles' name
NOTES = []           # things that change only noise or are exact, for the record


def approximation(msg):
    if msg not in APPROXIMATIONS:
        APPROXIMATIONS.append(msg)
        print("APPROXIMATION: " + msg, flush=True)


def note(msg):
    if msg not in NOTES:
        NOTES.append(msg)
        print("NOTE: " + msg, flush=True)


def log(msg):
    print("[cycles_reference] " + msg, flush=True)


def hard_exit(code):
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------

def parse_args(argv):
    args = {"scene": None, "out": None, "spp": None, "res": None, "seed": 0, "threads": 2,
            "defines": {}, "max_depth": None, "strategy": "mis", "roulette": True, "pattern": "sobol"}
    i = 0

    def value(opt):
        nonlocal i
        if i + 1 >= len(argv):
            raise SystemExit("error: %s needs a value\n\n%s" % (opt, USAGE))
        i += 1
        return argv[i]

    def integer(opt, text, lo=None):
        try:
            v = int(text)
        except ValueError:
            raise SystemExit("error: %s expects an integer, got '%s'" % (opt, text))
        if lo is not None and v < lo:
            raise SystemExit("error: %s must be >= %d" % (opt, lo))
        return v

    while i < len(argv):
        a = argv[i]
        if a in ("-h", "--help"):
            return None
        elif a == "--out":
            args["out"] = value(a)
        elif a == "--spp":
            args["spp"] = integer(a, value(a), 1)
        elif a == "--res":
            m = re.fullmatch(r"(\d+)[xX](\d+)", value(a))
            if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
                raise SystemExit("error: --res expects WxH, e.g. 256x256")
            args["res"] = (int(m.group(1)), int(m.group(2)))
        elif a == "--seed":
            args["seed"] = integer(a, value(a), 0)
        elif a == "--threads":
            args["threads"] = integer(a, value(a), 1)
        elif a == "--max-depth":
            args["max_depth"] = integer(a, value(a), -1)
        elif a == "--no-roulette":
            args["roulette"] = False
        elif a == "--strategy":
            args["strategy"] = value(a)
            if args["strategy"] not in ("mis", "bsdf"):
                raise SystemExit("error: --strategy expects mis or bsdf, got '%s'" % args["strategy"])
        elif a == "--pattern":
            args["pattern"] = value(a)
            if args["pattern"] not in ("sobol", "pmj"):
                raise SystemExit("error: --pattern expects sobol or pmj, got '%s'" % args["pattern"])
        elif a == "-D" or a.startswith("-D"):
            d = value(a) if a == "-D" else a[2:]
            if "=" not in d or not d.split("=", 1)[0]:
                raise SystemExit("error: -D expects name=value, got '%s'" % d)
            k, v = d.split("=", 1)
            args["defines"][k] = v
        elif a.startswith("-"):
            raise SystemExit("error: unknown option '%s'\n\n%s" % (a, USAGE))
        elif args["scene"] is None:
            args["scene"] = a
        else:
            raise SystemExit("error: more than one scene given ('%s', '%s')" % (args["scene"], a))
        i += 1
    if not args["scene"] or not args["out"]:
        raise SystemExit("error: need SCENE.xml and --out FILE.exr\n\n" + USAGE)
    return args


# --------------------------------------------------------------------------------------------
# XML with line numbers, <default> and $name substitution
# --------------------------------------------------------------------------------------------

class Node:
    __slots__ = ("tag", "attrs", "children", "line", "file")

    def __init__(self, tag, attrs, line, file):
        self.tag, self.attrs, self.children, self.line, self.file = tag, attrs, [], line, file

    def fail(self, msg, field=None):
        raise SceneError(msg, self.file, self.line, field)

    def attr(self, name, required=True, default=None):
        if name in self.attrs:
            return self.attrs[name]
        if required:
            self.fail("<%s> needs the attribute '%s'" % (self.tag, name), name)
        return default


def parse_xml(path):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SceneError("cannot read the scene: %s" % e, path)
    parser = xml.parsers.expat.ParserCreate()
    stack, root = [], []

    def start(tag, attrs):
        n = Node(tag, dict(attrs), parser.CurrentLineNumber, path)
        if stack:
            stack[-1].children.append(n)
        else:
            root.append(n)
        stack.append(n)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as e:
        raise SceneError("malformed XML: %s" % xml.parsers.expat.ErrorString(e.code), path, e.lineno)
    return root[0]


def substitute(root, defines):
    """Mitsuba 3's <default name value> plus -D overrides, then $name in every attribute."""
    params = {}
    for c in root.children:
        if c.tag == "default":
            unexpected = set(c.attrs) - {"name", "value"}
            if unexpected:
                c.fail("unexpected attribute '%s' on <default>" % sorted(unexpected)[0])
            params[c.attr("name")] = c.attr("value")
    used = set()
    for k, v in defines.items():
        params[k] = v
    pattern = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")

    def walk(n):
        if n.tag != "default":
            for k, v in list(n.attrs.items()):
                if "$" not in v:
                    continue

                def repl(m):
                    name = m.group(1)
                    if name not in params:
                        n.fail("undefined parameter '$%s' (add <default name=\"%s\" value=...> or -D %s=...)"
                               % (name, name, name), k)
                    used.add(name)
                    return params[name]

                n.attrs[k] = pattern.sub(repl, v)
                if "$" in n.attrs[k]:
                    n.fail("cannot substitute '%s'" % v, k)
        for c in n.children:
            walk(c)

    walk(root)
    for k in defines:
        if k not in used:
            note("-D %s=%s is not used by the scene" % (k, defines[k]))
    return params


# --------------------------------------------------------------------------------------------
# Properties and transforms
# --------------------------------------------------------------------------------------------

PROPERTY_TAGS = {"float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector", "transform"}


class Prop:
    __slots__ = ("kind", "value", "line")

    def __init__(self, kind, value, line):
        self.kind, self.value, self.line = kind, value, line


def floats(node, text, field, count=None):
    parts = [p for p in re.split(r"[,\s]+", text.strip()) if p]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        node.fail("cannot read numbers from '%s'" % text, field)
    if count is not None and len(vals) not in (count if isinstance(count, tuple) else (count,)):
        node.fail("expected %s numbers, got %d in '%s'" % (count, len(vals), text), field)
    return vals


def xyz(node, name, default):
    """A point/vector given as x=, y=, z= (missing ones default) or as value="x, y, z"."""
    if "value" in node.attrs:
        v = floats(node, node.attrs["value"], name, (1, 3))
        return np.array(v * 3 if len(v) == 1 else v, dtype=np.float64)
    out = []
    for axis, d in zip("xyz", default):
        out.append(float(floats(node, node.attrs[axis], name, 1)[0]) if axis in node.attrs else d)
    return np.array(out, dtype=np.float64)


def rotation(axis, deg):
    n = np.linalg.norm(axis)
    if n == 0:
        raise ValueError("zero rotation axis")
    x, y, z = axis / n
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    t = 1 - c
    m = np.eye(4)
    m[:3, :3] = [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                 [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                 [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]
    return m


def parse_transform(node, name):
    """<transform>: children applied in order, each one left-multiplies (Mitsuba 3)."""
    m = np.eye(4)
    for c in node.children:
        if c.tag == "matrix":
            v = floats(c, c.attr("value"), name + ".matrix", (9, 16))
            if len(v) == 9:
                t = np.eye(4)
                t[:3, :3] = np.array(v).reshape(3, 3)
            else:
                t = np.array(v).reshape(4, 4)
        elif c.tag == "translate":
            t = np.eye(4)
            t[:3, 3] = xyz(c, name + ".translate", (0.0, 0.0, 0.0))
        elif c.tag == "scale":
            if "value" in c.attrs and not any(a in c.attrs for a in "xyz"):
                v = floats(c, c.attrs["value"], name + ".scale", (1, 3))
                s = v * 3 if len(v) == 1 else v
            else:
                s = xyz(c, name + ".scale", (1.0, 1.0, 1.0))
            t = np.diag([s[0], s[1], s[2], 1.0])
        elif c.tag == "rotate":
            axis = xyz(c, name + ".rotate", (0.0, 0.0, 0.0)) if "value" not in c.attrs else \
                np.array(floats(c, c.attrs["value"], name + ".rotate", 3))
            ang = floats(c, c.attr("angle"), name + ".rotate.angle", 1)[0]
            try:
                t = rotation(axis, ang)
            except ValueError:
                c.fail("rotate needs a nonzero axis", name + ".rotate")
        elif c.tag == "lookat":
            o = np.array(floats(c, c.attr("origin"), name + ".lookat.origin", 3))
            tg = np.array(floats(c, c.attr("target"), name + ".lookat.target", 3))
            up = np.array(floats(c, c.attrs.get("up", "0, 1, 0"), name + ".lookat.up", 3))
            d = tg - o
            if np.linalg.norm(d) == 0:
                c.fail("lookat origin and target coincide", name + ".lookat")
            d /= np.linalg.norm(d)
            left = np.cross(up, d)
            if np.linalg.norm(left) < 1e-12:
                c.fail("lookat 'up' is parallel to the viewing direction", name + ".lookat.up")
            left /= np.linalg.norm(left)
            new_up = np.cross(d, left)
            t = np.eye(4)
            t[:3, 0], t[:3, 1], t[:3, 2], t[:3, 3] = left, new_up, d, o
        else:
            c.fail("unknown transform element <%s> (known: matrix, translate, scale, rotate, lookat)" % c.tag, name)
        m = t @ m
    if not np.allclose(m[3], [0, 0, 0, 1]):
        node.fail("projective transforms are not supported", name)
    return m


def parse_property(n):
    name = n.attr("name")
    k = n.tag
    if k == "float":
        v = floats(n, n.attr("value"), name, 1)[0]
    elif k == "integer":
        try:
            v = int(n.attr("value"))
        except ValueError:
            n.fail("expected an integer, got '%s'" % n.attrs["value"], name)
    elif k == "boolean":
        s = n.attr("value").strip().lower()
        if s not in ("true", "false"):
            n.fail("expected true or false, got '%s'" % n.attrs["value"], name)
        v = s == "true"
    elif k == "string":
        v = n.attr("value")
    elif k in ("rgb", "spectrum"):
        if k == "spectrum" and ("filename" in n.attrs or ":" in n.attrs.get("value", "")):
            n.fail("only uniform <spectrum value=\"x\"> is supported (RGB rendering)", name)
        vals = floats(n, n.attr("value"), name, (1, 3) if k == "rgb" else 1)
        v = tuple(vals * 3 if len(vals) == 1 else vals)
    elif k in ("point", "vector"):
        v = xyz(n, name, (0.0, 0.0, 0.0))
    elif k == "transform":
        v = parse_transform(n, name)
    else:
        n.fail("unknown property tag <%s>" % k, name)
    return name, Prop("rgb" if k == "spectrum" else k, v, n.line)


class Plugin:
    """An XML object (<bsdf>, <shape>, ...): its properties, checked off as they are read, and its
    nested objects. finish() fails on any property nobody read, so nothing is dropped silently."""

    def __init__(self, node, what):
        self.node = node
        self.tag = node.tag
        self.type = node.attr("type")
        self.id = node.attrs.get("id", "")
        self.where = "%s '%s'" % (what, self.id) if self.id else what
        self.props, self.children, self.used = {}, [], set()
        for c in node.children:
            if c.tag in PROPERTY_TAGS:
                name, p = parse_property(c)
                if name in self.props:
                    c.fail("property '%s' is given twice" % name, self.where + "." + name)
                self.props[name] = p
            else:
                self.children.append(c)

    def fail(self, msg, prop=None):
        line = self.props[prop].line if prop in self.props else self.node.line
        raise SceneError(msg, self.node.file, line, self.where + ("." + prop if prop else ""))

    def has(self, name):
        return name in self.props

    def get(self, name, kinds, default):
        p = self.props.get(name)
        self.used.add(name)
        if p is None:
            return default
        if p.kind not in kinds:
            self.fail("expected <%s>, got <%s>" % ("> or <".join(kinds), p.kind), name)
        return p.value

    def float(self, name, default=None):
        v = self.get(name, ("float", "integer"), default)
        return None if v is None else float(v)

    def int(self, name, default=None):
        return self.get(name, ("integer",), default)

    def bool(self, name, default=False):
        return self.get(name, ("boolean",), default)

    def str(self, name, default=None):
        return self.get(name, ("string",), default)

    def rgb(self, name, default=None):
        v = self.get(name, ("rgb", "float", "integer"), default)
        if isinstance(v, (int, float)):
            v = (float(v),) * 3
        return v

    def transform(self, name="to_world"):
        return self.get(name, ("transform",), np.eye(4))

    def point(self, name, default):
        return self.get(name, ("point", "vector"), default)

    def ignore(self, *names):
        self.used.update(names)

    def finish(self):
        for k in self.props:
            if k not in self.used:
                self.fail("<%s type=\"%s\"> does not support the property '%s' here (it would change "
                          "the image, so it is not ignored)" % (self.tag, self.type, k), k)


# --------------------------------------------------------------------------------------------
# Mitsuba's named IORs and Fresnel helpers
# --------------------------------------------------------------------------------------------

IOR_TABLE = {  # Mitsuba 3 include/mitsuba/render/ior.h
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277,
    "carbon dioxide": 1.00045, "water": 1.3330, "acetone": 1.36, "ethanol": 1.361,
    "carbon tetrachloride": 1.461, "glycerol": 1.4729, "benzene": 1.501, "silicone oil": 1.52045,
    "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458, "pyrex": 1.470,
    "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046, "sodium chloride": 1.544,
    "amber": 1.55, "pet": 1.5750, "diamond": 2.419,
}


def lookup_ior(p, name, default_name):
    if p.has(name) and p.props[name].kind == "string":
        s = p.str(name).strip().lower()
        if s not in IOR_TABLE:
            p.fail("unknown IOR name '%s' (known: %s)" % (s, ", ".join(sorted(IOR_TABLE))), name)
        return IOR_TABLE[s]
    v = p.float(name, None)
    return IOR_TABLE[default_name] if v is None else v


def fresnel_dielectric_np(cos_i, eta):
    """Mitsuba 3's fresnel(): unpolarised reflectance, cos_theta_t (signed) and eta_ti."""
    cos_i = np.asarray(cos_i, dtype=np.float64)
    outside = cos_i >= 0
    eta_it = np.where(outside, eta, 1.0 / eta)
    eta_ti = np.where(outside, 1.0 / eta, eta)
    ct2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti
    ci = np.abs(cos_i)
    ct = np.sqrt(np.maximum(ct2, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        a_s = (ci - eta_it * ct) / (ci + eta_it * ct)
        a_p = (ct - eta_it * ci) / (ct + eta_it * ci)
        r = 0.5 * (a_s * a_s + a_p * a_p)
    special = (eta == 1.0) | (ci == 0.0)
    r = np.where(special, 0.0 if eta == 1.0 else 1.0, r)
    return r, np.where(cos_i >= 0, -ct, ct), eta_ti


def fresnel_diffuse_reflectance(eta):
    """Mitsuba 3's fit of the hemispherical average of the dielectric Fresnel reflectance."""
    inv = 1.0 / eta
    if eta < 1.0:
        return 0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881]
    acc = c[-1]
    for k in reversed(c[:-1]):
        acc = acc * inv + k
    return acc


# --------------------------------------------------------------------------------------------
# Microfacet tables for roughplastic (numerical, in numpy)
# --------------------------------------------------------------------------------------------

ROUGH_RES = 64  # Mitsuba 3's MI_ROUGH_TRANSMITTANCE_RES


def smith_g1(dist, alpha, vx, vy, vz, mdotv):
    """Mitsuba 3 MicrofacetDistribution::smith_g1 (Beckmann: its rational approximation)."""
    xy = alpha * alpha * (vx * vx + vy * vy)
    with np.errstate(divide="ignore", invalid="ignore"):
        tt = xy / (vz * vz)
        if dist == "beckmann":
            a = 1.0 / np.sqrt(tt)
            g = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
        else:
            g = 2.0 / (1.0 + np.sqrt(1.0 + tt))
    g = np.where(xy == 0, 1.0, g)
    return np.where(mdotv * vz <= 0, 0.0, g)


_TABLE_CACHE = {}


def rough_tables(dist, alpha, eta):
    """For Mitsuba 3's roughplastic: at mu_j = max(1e-6, j/63), j = 0..63, the rough dielectric
    interface's reflectance R(mu) and transmittance T(mu) (what Mitsuba's eval_reflectance /
    eval_transmittance compute by quadrature over visible normals), the internal reflectance
    (Mitsuba: mean_j(R(mu_j, 1/eta) mu_j) * 2) and the albedo A(mu) of Cycles' Glossy BSDF (same
    D and Smith G, no Fresnel). Integrated here over microfacet normals m with Gauss-Legendre in
    u, tan(theta_m) = alpha tan(pi u / 2), and phi."""
    key = (dist, round(alpha, 9), round(eta, 9))
    if key in _TABLE_CACHE:
        return _TABLE_CACHE[key]
    xu, wu = np.polynomial.legendre.leggauss(384)
    u, wu = 0.5 * xu + 0.5, 0.5 * wu
    t = np.tan(0.5 * math.pi * u)
    theta = np.arctan(alpha * t)
    jac = wu * alpha / (1.0 + (alpha * t) ** 2) * 0.5 * math.pi * (1.0 + t * t)
    cm, sm = np.cos(theta), np.sin(theta)
    if dist == "beckmann":
        D = np.exp(-t * t) / (math.pi * alpha * alpha * cm ** 4)
    else:
        D = 1.0 / (math.pi * alpha * alpha * cm ** 4 * (1.0 + t * t) ** 2)
    xp, wp = np.polynomial.legendre.leggauss(192)
    phi, wp = 0.5 * math.pi * (xp + 1.0), 0.5 * math.pi * wp  # [0, pi], doubled by symmetry below
    base = (D * sm * jac)[:, None] * (2.0 * wp)[None, :]
    mx = sm[:, None] * np.cos(phi)[None, :]
    my = sm[:, None] * np.sin(phi)[None, :]
    mz = np.broadcast_to(cm[:, None], mx.shape)
    mus = np.maximum(1e-6, np.linspace(0.0, 1.0, ROUGH_RES))
    R, T, A, Rint = (np.zeros(ROUGH_RES) for _ in range(4))
    for j, mu in enumerate(mus):
        s = math.sqrt(max(0.0, 1.0 - mu * mu))
        c = s * mx + mu * mz  # wi . m, wi = (s, 0, mu)
        w = base * np.maximum(c, 0.0)
        wsum = w.sum()
        if wsum <= 0:
            continue
        # reflection
        ox, oy, oz = 2 * c * mx - s, 2 * c * my, 2 * c * mz - mu
        g1o = smith_g1(dist, alpha, ox, oy, oz, c) * (oz > 0)
        for e, dest in ((eta, R), (1.0 / eta, Rint)):
            F = fresnel_dielectric_np(c, e)[0]
            dest[j] = (w * F * g1o).sum() / wsum
        g1i = smith_g1(dist, alpha, s, 0.0, mu, 1.0)
        A[j] = g1i / mu * (w * g1o).sum()
        # transmission (Mitsuba's refract(wi, m, cos_theta_t, eta_ti))
        F, ct, eta_ti = fresnel_dielectric_np(c, eta)
        k = c * eta_ti + ct
        tx, ty, tz = mx * k - s * eta_ti, my * k, mz * k - mu * eta_ti
        g1t = smith_g1(dist, alpha, tx, ty, tz, mx * tx + my * ty + mz * tz) * (tz * mu < 0)
        T[j] = (w * (1.0 - F) * g1t).sum() / wsum
    internal = float(np.mean(Rint * mus) * 2.0)
    out = {"mu": mus, "R": R, "T": T, "A": A, "internal": internal}
    _TABLE_CACHE[key] = out
    return out


def mitsuba_lerp(table, mu):
    """Mitsuba's lerp_gather over a 64-entry table indexed by cos(theta)."""
    x = np.clip(mu, 0.0, 1.0) * (len(table) - 1)
    i = np.minimum(x.astype(int), len(table) - 2)
    f = x - i
    return table[i] * (1 - f) + table[i + 1] * f


def cosine_mean(f):
    """2 * integral_0^1 f(mu) mu dmu, by a fine midpoint rule."""
    mu = (np.arange(20000) + 0.5) / 20000
    return float(2.0 * np.mean(f(mu) * mu))


# --------------------------------------------------------------------------------------------
# Meshes
# --------------------------------------------------------------------------------------------

class MeshData:
    """World-space triangles. normals: per corner (M, 3, 3) for smooth shading, or None for
    flat (face normals). uvs: per corner (M, 3, 2) in Blender's convention, or None."""

    def __init__(self, P, tris, normals=None, uvs=None):
        self.P, self.tris, self.normals, self.uvs = P, tris, normals, uvs


def normalize_rows(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 0, v / np.where(n > 0, n, 1.0), v)


def read_obj(path, where, fail):
    """Wavefront OBJ as Mitsuba 3 reads it: v, vt, vn; faces v, v/vt, v//vn, v/vt/vn; polygons
    fan-triangulated (c0, ci, ci+1). Returns positions, per-corner index arrays (0-based; -1 for
    a missing vt/vn) and the source line of each triangle."""
    try:
        with open(path, "rb") as f:
            text = f.read().decode("utf-8", "replace")
    except OSError as e:
        fail("cannot read mesh '%s': %s" % (path, e))
    v, vt, vn = [], [], []
    cv, ct, cn, lines = [], [], [], []
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        k = parts[0]
        if k == "v":
            v.append(parts[1:4])
        elif k == "vt":
            vt.append(parts[1:3])
        elif k == "vn":
            vn.append(parts[1:4])
        elif k == "f":
            corners = []
            for tok in parts[1:]:
                s = tok.split("/")
                try:
                    idx = [int(x) if x else 0 for x in s[:3]] + [0] * (3 - len(s[:3]))
                except ValueError:
                    fail("%s:%d: cannot read face corner '%s'" % (path, lineno, tok))
                if min(idx) < 0:
                    fail("%s:%d: negative (relative) OBJ indices are not supported" % (path, lineno))
                if idx[0] == 0:
                    fail("%s:%d: face corner '%s' has no vertex index" % (path, lineno, tok))
                corners.append(idx)
            if len(corners) < 3:
                fail("%s:%d: face with fewer than 3 corners" % (path, lineno))
            for i in range(1, len(corners) - 1):
                for c in (corners[0], corners[i], corners[i + 1]):
                    cv.append(c[0])
                    ct.append(c[1])
                    cn.append(c[2])
                lines.append(lineno)
        # other statements (o, g, s, usemtl, mtllib, l, ...) do not affect Mitsuba's mesh
    try:
        V = np.array(v, dtype=np.float64).reshape(-1, 3)
        VT = np.array(vt, dtype=np.float64).reshape(-1, 2) if vt else np.zeros((0, 2))
        VN = np.array(vn, dtype=np.float64).reshape(-1, 3) if vn else np.zeros((0, 3))
    except ValueError:
        fail("%s: malformed v/vt/vn line (each needs 3, 2, 3 numbers)" % path)
    cv = np.array(cv, dtype=np.int64).reshape(-1, 3) - 1
    ct = np.array(ct, dtype=np.int64).reshape(-1, 3) - 1
    cn = np.array(cn, dtype=np.int64).reshape(-1, 3) - 1
    lines = np.array(lines, dtype=np.int64)
    for arr, n, what in ((cv, len(V), "vertex"), (ct, len(VT), "texture coordinate"), (cn, len(VN), "normal")):
        bad = np.nonzero((arr >= n).any(axis=1))[0]
        if len(bad):
            fail("%s:%d: reference to a %s index beyond the %d defined" % (path, lines[bad[0]], what, n))
    if len(cv) == 0:
        fail("%s: no faces" % path)
    return V, VT, VN, cv, ct, cn


PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


def read_ply(path, fail):
    """PLY, ASCII or binary little-endian: vertex x y z [nx ny nz] [u v | s t | texture_u texture_v],
    face vertex_indices (or vertex_index) lists, fan-triangulated."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        fail("cannot read mesh '%s': %s" % (path, e))
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        fail("%s: not a PLY file" % path)
    nl = data.index(b"\n", end)
    header = data[:nl].decode("ascii", "replace").splitlines()
    body = data[nl + 1:]
    fmt, elements = None, []
    for ln in header[1:]:
        p = ln.split()
        if not p or p[0] in ("comment", "obj_info", "end_header"):
            continue
        if p[0] == "format":
            fmt = p[1]
        elif p[0] == "element":
            elements.append({"name": p[1], "count": int(p[2]), "props": []})
        elif p[0] == "property":
            if p[1] == "list":
                elements[-1]["props"].append(("list", p[4], PLY_TYPES[p[2]], PLY_TYPES[p[3]]))
            else:
                elements[-1]["props"].append(("scalar", p[2], PLY_TYPES[p[1]]))
    if fmt not in ("ascii", "binary_little_endian"):
        fail("%s: PLY format '%s' is not supported (ascii, binary_little_endian)" % (path, fmt))
    verts, faces = None, []
    if fmt == "ascii":
        tokens = body.split()
        pos = 0
        for el in elements:
            rows = []
            for _ in range(el["count"]):
                row = {}
                for pr in el["props"]:
                    if pr[0] == "scalar":
                        row[pr[1]] = float(tokens[pos])
                        pos += 1
                    else:
                        n = int(tokens[pos])
                        row[pr[1]] = [int(x) for x in tokens[pos + 1:pos + 1 + n]]
                        pos += 1 + n
                rows.append(row)
            if el["name"] == "vertex":
                verts = {k: np.array([r[k] for r in rows]) for k in (rows[0].keys() if rows else [])}
            elif el["name"] == "face":
                key = [pr[1] for pr in el["props"] if pr[0] == "list"]
                if not key:
                    fail("%s: face element without a vertex index list" % path)
                faces = [r[key[0]] for r in rows]
    else:
        pos = 0
        for el in elements:
            if all(pr[0] == "scalar" for pr in el["props"]):
                dt = np.dtype([(pr[1], "<" + pr[2]) for pr in el["props"]])
                arr = np.frombuffer(body, dtype=dt, count=el["count"], offset=pos)
                pos += dt.itemsize * el["count"]
                if el["name"] == "vertex":
                    verts = {k: arr[k].astype(np.float64) for k in dt.names}
            elif el["name"] == "face":
                lists = [pr for pr in el["props"] if pr[0] == "list"]
                if len(el["props"]) != 1 or len(lists) != 1:
                    fail("%s: binary face elements with extra properties are not supported" % path)
                _, _, ct_, it = lists[0]
                cdt, idt = np.dtype("<" + ct_), np.dtype("<" + it)
                for _ in range(el["count"]):
                    n = int(np.frombuffer(body, cdt, 1, pos)[0])
                    pos += cdt.itemsize
                    faces.append(np.frombuffer(body, idt, n, pos).astype(np.int64))
                    pos += idt.itemsize * n
            else:
                fail("%s: binary element '%s' with list properties is not supported" % (path, el["name"]))
    if verts is None or not all(k in verts for k in "xyz") or not faces:
        fail("%s: needs vertex x y z and faces" % path)
    V = np.stack([verts["x"], verts["y"], verts["z"]], axis=1)
    N = np.stack([verts["nx"], verts["ny"], verts["nz"]], axis=1) if all(k in verts for k in ("nx", "ny", "nz")) else None
    UV = None
    for a, b in (("u", "v"), ("s", "t"), ("texture_u", "texture_v")):
        if a in verts and b in verts:
            UV = np.stack([verts[a], verts[b]], axis=1)
    tris = []
    for f in faces:
        for i in range(1, len(f) - 1):
            tris.append((f[0], f[i], f[i + 1]))
    tris = np.array(tris, dtype=np.int64).reshape(-1, 3)
    if tris.size and (tris.max() >= len(V) or tris.min() < 0):
        fail("%s: face index out of range" % path)
    return V, N, UV, tris


def angle_weighted_normals(P, tris, keys):
    """Mitsuba 3's Mesh::recompute_vertex_normals: face normals weighted by the corner angle,
    summed per Mitsuba vertex (keys: the vertex id of each corner), normalised. Returns per-corner
    normals (M, 3, 3)."""
    p = P[tris]  # (M, 3, 3)
    n = normalize_rows(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    acc = np.zeros((keys.max() + 1, 3))
    for i in range(3):
        d0 = normalize_rows(p[:, (i + 1) % 3] - p[:, i])
        d1 = normalize_rows(p[:, (i + 2) % 3] - p[:, i])
        ang = np.arccos(np.clip((d0 * d1).sum(axis=1), -1.0, 1.0))
        np.add.at(acc, keys[:, i], n * ang[:, None])
    acc = normalize_rows(acc)
    return acc[keys]


def transform_mesh(P, normals, M):
    """Positions by M, per-corner normals by M's inverse transpose (renormalised)."""
    P = P @ M[:3, :3].T + M[:3, 3]
    if normals is not None:
        nt = np.linalg.inv(M[:3, :3]).T
        normals = normalize_rows(normals @ nt.T)
    return P, normals


def finalize_mesh(P, tris, normals, uvs, M, flip_normals, where):
    """World transform, winding (reversed where det(M) < 0, so the geometric normal follows the
    inverse-transpose-transformed normal like Mitsuba's), flip_normals, zero-area triangles
    dropped (Mitsuba 3 drops them too)."""
    P, normals = transform_mesh(P, normals, M)
    det = np.linalg.det(M[:3, :3])
    if det == 0:
        raise SceneError("to_world is singular", None, None, where)
    rev = det < 0
    if rev:
        approximation("%s: to_world mirrors (det < 0): winding reversed so the geometric normal follows the "
                      "inverse-transpose-transformed normal (as for Mitsuba's analytic shapes); Mitsuba's own "
                      "treatment of mirrored meshes was not verified" % where)
    if flip_normals:
        rev = not rev
        if normals is not None:
            normals = -normals
    if rev:
        tris = tris[:, ::-1]
        if normals is not None:
            normals = normals[:, ::-1]
        if uvs is not None:
            uvs = uvs[:, ::-1]
    p = P[tris]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    keep = (area2 > 0) & (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    dropped = int((~keep).sum())
    if dropped:
        note("%s: dropped %d zero-area triangle(s), as Mitsuba 3 does" % (where, dropped))
    tris = tris[keep]
    if normals is not None:
        normals = normals[keep]
    if uvs is not None:
        uvs = uvs[keep]
    if len(tris) == 0:
        raise SceneError("mesh has no triangle of nonzero area", None, None, where)
    return MeshData(P, tris, normals, uvs)


def make_rectangle():
    P = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    # Mitsuba uv = ((x+1)/2, (y+1)/2) with v = 0 at the bitmap's top row; Blender's v = 0 is the
    # bottom row, so Blender v = 1 - v_mitsuba.
    uv_m = (P[:, :2] + 1) / 2
    uv = np.stack([uv_m[:, 0], 1 - uv_m[:, 1]], axis=1)[tris]
    return P, tris, None, uv


def make_cube():
    """[-1, 1]^3, 12 triangles, outward per-face normals (flat shading)."""
    P, tris, uvs = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            u_ax, v_ax = [a for a in range(3) if a != axis]
            base = len(P)
            quad = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
            for a, b in quad:
                p = [0.0, 0.0, 0.0]
                p[axis], p[u_ax], p[v_ax] = sign, a, b
                P.append(p)
            n = np.zeros(3)
            n[axis] = sign
            t0 = [base, base + 1, base + 2]
            t1 = [base, base + 2, base + 3]
            e = np.cross(np.array(P[base + 1]) - P[base], np.array(P[base + 2]) - P[base])
            if np.dot(e, n) < 0:
                t0, t1 = t0[::-1], t1[::-1]
            tris += [t0, t1]
            for t in (t0, t1):
                uvs.append([[(P[i][u_ax] + 1) / 2, 1 - (P[i][v_ax] + 1) / 2] for i in t])
    return np.array(P, dtype=np.float64), np.array(tris), None, np.array(uvs)


SPHERE_SEGMENTS = (512, 256)  # (around, pole to pole): fine, for mirrors and glass
# Cycles 3.4 loses light from meshes of many small emitting triangles: a sphere light of radius
# 0.4 over a plane read, against the closed form E = pi L r^2 cos / d^2 (ratios after each
# polyhedron's own area deficit), -0.01 % as 64x32 segments, -0.04 % as 128x64 and -0.39 % as
# 512x256 (docs/validation.md, "dining-room's last offset"). Emitting spheres: 128x64, pushed
# out to the sphere's area. (Not every sphere: the coarser facets under smooth normals cost a
# glass sphere in a furnace 3 % at its silhouette.)
EMITTER_SPHERE_SEGMENTS = (128, 64)


def make_sphere(segments=SPHERE_SEGMENTS, match_area=False):
    """Unit UV sphere with exact radial per-corner normals; with match_area its vertices are pushed
    out so that the inscribed polyhedron has the sphere's area (and so, by Cauchy's formula, its
    mean projected area: what a light's power and far irradiance depend on). Mitsuba's uv = (phi/2pi, theta/pi) with phi = atan2(y, x),
    theta = acos(z); Blender v = 1 - v_mitsuba."""
    nu, nv = segments
    th = np.linspace(0, math.pi, nv + 1)
    ph = np.linspace(0, 2 * math.pi, nu + 1)
    T, Ph = np.meshgrid(th, ph, indexing="ij")  # (nv+1, nu+1), seam column duplicated
    P = np.stack([np.sin(T) * np.cos(Ph), np.sin(T) * np.sin(Ph), np.cos(T)], axis=-1).reshape(-1, 3)
    P[np.abs(P) < 1e-15] = 0.0
    idx = np.arange((nv + 1) * (nu + 1)).reshape(nv + 1, nu + 1)
    a, b = idx[:-1, :-1], idx[:-1, 1:]
    c, d = idx[1:, 1:], idx[1:, :-1]
    # outward orientation: theta grows towards -z, phi around +z
    t0 = np.stack([a, d, c], axis=-1).reshape(-1, 3)
    t1 = np.stack([a, c, b], axis=-1).reshape(-1, 3)
    tris = np.concatenate([t0, t1])
    p = P[tris]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)  # twice each area
    tris = tris[area > 1e-14]  # the degenerate pole triangles
    scale = math.sqrt(4 * math.pi / (0.5 * area.sum())) if match_area else 1.0
    uv_m = np.stack([Ph.ravel() / (2 * math.pi), T.ravel() / math.pi], axis=1)
    uv = np.stack([uv_m[:, 0], 1 - uv_m[:, 1]], axis=1)[tris]
    normals = P[tris]  # unit sphere: the normal is the position
    return P * scale, tris, normals, uv


# --------------------------------------------------------------------------------------------
# Scene description (parsed, before Blender)
# --------------------------------------------------------------------------------------------

class Texture:
    def __init__(self, filename, filter_type, wrap, raw, where):
        self.filename, self.filter_type, self.wrap, self.raw, self.where = filename, filter_type, wrap, raw, where


class Bsdf:
    def __init__(self, type_, where, params, nested):
        self.type, self.where, self.params, self.nested = type_, where, params, nested


class Scene:
    def __init__(self):
        self.bsdfs = {}     # id -> Bsdf
        self.textures = {}  # id -> Texture
        self.shapes = []    # dicts
        self.env = None     # ("constant", rgb) | ("envmap", file, scale, to_world)
        self.sensor = None
        self.film = None
        self.integrator = {"max_depth": -1, "rr_depth": 5}
        self.spp = 4
        self.sampler = "independent (Mitsuba's default)"


class Loader:
    def __init__(self, path):
        self.path = os.path.abspath(path)
        self.dir = os.path.dirname(self.path)
        self.scene = Scene()
        self.ids = {}

    def register(self, node, kind, obj):
        i = node.attrs.get("id")
        if i:
            if i in self.ids:
                node.fail("duplicate id '%s'" % i, "id")
            self.ids[i] = (kind, obj)

    def resolve(self, ref, kinds):
        i = ref.attr("id")
        if i not in self.ids:
            ref.fail("reference to undefined id '%s' (ids must be defined before use)" % i, "id")
        kind, obj = self.ids[i]
        if kind not in kinds:
            ref.fail("'%s' is a <%s>, expected %s" % (i, kind, " or ".join(kinds)), "id")
        return kind, obj

    def load(self, root):
        if root.tag != "scene":
            root.fail("the root element must be <scene>")
        ver = root.attrs.get("version", "")
        try:
            major = int(ver.split(".")[0])
        except ValueError:
            root.fail("cannot read the scene version '%s'" % ver, "version")
        if major < 2:
            root.fail("scene version %s is a Mitsuba 0.x file (camelCase names); only 2.x/3.x" % ver, "version")
        for c in root.children:
            t = c.tag
            if t == "default":
                continue
            elif t == "integrator":
                self.read_integrator(c)
            elif t == "sensor":
                self.read_sensor(c)
            elif t == "bsdf":
                self.read_bsdf(c, "bsdf")
            elif t == "texture":
                tex = self.read_texture(c, "texture")
                if not c.attrs.get("id"):
                    c.fail("a top-level <texture> needs an id")
                self.register(c, "texture", tex)
            elif t == "shape":
                self.read_shape(c)
            elif t == "emitter":
                self.read_env(c)
            elif t == "medium":
                self.register(c, "medium", None)
                approximation("participating media are ignored (<medium> at line %d)" % c.line)
            else:
                c.fail("<%s> is not supported at the top level (known: default, integrator, sensor, bsdf, "
                       "texture, shape, emitter, medium)" % t)
        if self.scene.sensor is None:
            root.fail("scene has no <sensor>")
        return self.scene

    # -- integrator, sensor, film, sampler ---------------------------------------------------
    def read_integrator(self, n):
        p = Plugin(n, "integrator")
        if p.type != "path":
            p.fail("integrator '%s' is not supported (path only)" % p.type, None)
        for c in p.children:
            c.fail("unexpected <%s> inside the integrator" % c.tag)
        md = p.int("max_depth", -1)
        if md < -1:
            p.fail("max_depth must be >= -1", "max_depth")
        self.scene.integrator["max_depth"] = md
        self.scene.integrator["rr_depth"] = p.int("rr_depth", 5)
        if p.bool("hide_emitters", False):
            p.fail("hide_emitters=true is not supported", "hide_emitters")
        p.finish()

    def read_sensor(self, n):
        p = Plugin(n, "sensor")
        if self.scene.sensor is not None:
            p.fail("only one <sensor> is supported")
        if p.type != "perspective":
            p.fail("sensor '%s' is not supported (perspective only)" % p.type)
        if not p.has("fov"):
            p.fail("the perspective sensor needs 'fov' (focal_length is not supported)", "fov")
        s = {"fov": p.float("fov"), "fov_axis": p.str("fov_axis", "x"),
             "near": p.float("near_clip", 1e-2), "far": p.float("far_clip", 1e4),
             "to_world": p.transform("to_world"), "where": p.where, "node": n}
        if s["fov_axis"] not in ("x", "y", "smaller", "larger", "diagonal"):
            p.fail("fov_axis must be x, y, smaller, larger or diagonal", "fov_axis")
        if not 0 < s["fov"] < 180:
            p.fail("fov must be in (0, 180) degrees", "fov")
        p.ignore("focus_distance")  # only a thin lens uses it; Mitsuba's perspective ignores it
        if p.has("shutter_open") or p.has("shutter_close"):
            p.ignore("shutter_open", "shutter_close")
            note("sensor shutter times ignored: the scene has no motion")
        p.finish()
        self.register(n, "sensor", None)
        film = None
        for c in p.children:
            if c.tag == "film":
                if film is not None:
                    c.fail("only one <film> is supported")
                film = self.read_film(c)
            elif c.tag == "sampler":
                self.read_sampler(c)
            elif c.tag == "medium" or (c.tag == "ref" and self.resolve(c, ("medium",))):
                approximation("participating media are ignored (sensor medium at line %d)" % c.line)
            else:
                c.fail("unexpected <%s> inside the sensor" % c.tag)
        if film is None:
            # Mitsuba's default film: hdrfilm 768x576 with a gaussian filter
            film = {"width": 768, "height": 576, "filter": ("gaussian", 0.5)}
        self.scene.sensor, self.scene.film = s, film

    def read_film(self, n):
        p = Plugin(n, "film")
        if p.type != "hdrfilm":
            p.fail("film '%s' is not supported (hdrfilm)" % p.type)
        f = {"width": p.int("width", 768), "height": p.int("height", 576), "filter": ("gaussian", 0.5)}
        pf = p.str("pixel_format", "rgb")
        if pf.lower() not in ("rgb", "rgba"):
            p.fail("pixel_format '%s' would change the output; only rgb/rgba" % pf, "pixel_format")
        p.ignore("component_format", "file_format", "banner", "high_quality_edges")
        for k in ("crop_offset_x", "crop_offset_y", "crop_width", "crop_height"):
            if p.has(k):
                p.fail("film cropping is not supported", k)
        if p.has("sample_border"):
            if p.bool("sample_border"):
                p.fail("sample_border=true is not supported", "sample_border")
        if p.has("rfilter"):
            p.fail("rfilter must be an element", "rfilter")
        nf = 0
        for c in p.children:
            if c.tag != "rfilter":
                c.fail("unexpected <%s> inside the film" % c.tag)
            nf += 1
            if nf > 1:
                c.fail("only one <rfilter> is supported")
            r = Plugin(c, "rfilter")
            if r.type == "box":
                f["filter"] = ("box", r.float("radius", 0.5))
            elif r.type == "tent":
                f["filter"] = ("tent", r.float("radius", 1.0))
            elif r.type == "gaussian":
                f["filter"] = ("gaussian", r.float("stddev", 0.5))
            else:
                r.fail("rfilter '%s' is not supported (box, tent, gaussian)" % r.type)
            for cc in r.children:
                cc.fail("unexpected <%s> inside the rfilter" % cc.tag)
            r.finish()
        p.finish()
        if f["width"] < 1 or f["height"] < 1:
            p.fail("film width/height must be >= 1")
        return f

    def read_sampler(self, n):
        p = Plugin(n, "sampler")
        if p.type not in ("independent", "stratified", "multijitter", "orthogonal", "ldsampler"):
            p.fail("sampler '%s' is not supported" % p.type)
        self.scene.spp = p.int("sample_count", 4)
        p.ignore("seed", "jitter", "strength")
        for c in p.children:
            c.fail("unexpected <%s> inside the sampler" % c.tag)
        p.finish()
        self.scene.sampler = p.type

    # -- textures and BSDFs ------------------------------------------------------------------
    def read_texture(self, n, what):
        p = Plugin(n, what)
        if p.type != "bitmap":
            p.fail("texture '%s' is not supported (bitmap only)" % p.type)
        if p.has("to_uv"):
            p.fail("to_uv is not supported", "to_uv")
        fname = p.str("filename")
        if not fname:
            p.fail("a bitmap needs a filename", "filename")
        full = os.path.normpath(os.path.join(self.dir, fname))
        if not os.path.isfile(full):
            p.fail("texture file not found: %s" % full, "filename")
        ft = p.str("filter_type", "bilinear")
        if ft not in ("bilinear", "nearest"):
            p.fail("filter_type must be bilinear or nearest", "filter_type")
        wrap = p.str("wrap_mode", "repeat")
        if wrap not in ("repeat", "clamp"):
            p.fail("wrap_mode '%s' is not supported (repeat, clamp: Blender 3.4 has no mirror)" % wrap, "wrap_mode")
        raw = p.bool("raw", False)
        if p.has("format"):
            p.fail("format is not supported", "format")
        for c in p.children:
            c.fail("unexpected <%s> inside the bitmap" % c.tag)
        p.finish()
        return Texture(full, ft, wrap, raw, p.where)

    def color_param(self, p, name, default):
        """rgb/float constant, or a texture given as a child <texture name=...> or <ref name=...>."""
        tex = p.textures.get(name)
        if tex is not None:
            if p.has(name):
                p.fail("'%s' is given twice (property and texture)" % name, name)
            return tex
        return p.rgb(name, default)

    def read_bsdf(self, n, what):
        p = Plugin(n, what)
        p.textures, nested = {}, []
        for c in p.children:
            if c.tag == "bsdf":
                nested.append(self.read_bsdf(c, p.where + ".bsdf"))
            elif c.tag == "texture":
                name = c.attr("name")
                if name in p.textures:
                    c.fail("texture '%s' given twice" % name)
                p.textures[name] = self.read_texture(c, p.where + "." + name)
            elif c.tag == "ref":
                kind, obj = self.resolve(c, ("bsdf", "texture"))
                if kind == "bsdf":
                    nested.append(obj)
                else:
                    name = c.attr("name")
                    p.textures[name] = obj
            else:
                c.fail("unexpected <%s> inside <bsdf type=\"%s\">" % (c.tag, p.type))
        t = p.type
        params = {}
        if t == "twosided":
            if len(nested) not in (1, 2):
                p.fail("twosided needs one or two nested BSDFs")
            for b in nested:
                if b.type in ("dielectric", "roughdielectric", "thindielectric") or b.type == "twosided":
                    p.fail("twosided cannot nest '%s' (Mitsuba rejects BSDFs with transmission)" % b.type)
        elif nested:
            p.fail("bsdf '%s' does not take a nested BSDF" % t)
        if t == "diffuse":
            params["reflectance"] = self.color_param(p, "reflectance", (0.5,) * 3)
        elif t in ("dielectric", "roughdielectric"):
            params["int_ior"] = lookup_ior(p, "int_ior", "bk7")
            params["ext_ior"] = lookup_ior(p, "ext_ior", "air")
            sr = p.rgb("specular_reflectance", (1.0,) * 3)
            st = p.rgb("specular_transmittance", (1.0,) * 3)
            if any(k in p.textures for k in ("specular_reflectance", "specular_transmittance")):
                p.fail("textured dielectric weights are not supported")
            if tuple(sr) != tuple(st):
                p.fail("specular_reflectance != specular_transmittance: Cycles' Glass BSDF has one colour",
                       "specular_reflectance")
            params["color"] = tuple(sr)
            if t == "roughdielectric":
                self.read_microfacet(p, params)
        elif t in ("conductor", "roughconductor"):
            material = p.str("material", "none")
            if material != "none":
                p.fail("named conductor materials are not supported (give eta and k)", "material")
            if "eta" in p.textures or "k" in p.textures:
                p.fail("textured eta/k are not supported")
            if p.has("eta") or p.has("k"):
                params["eta"] = p.rgb("eta", (0.0,) * 3)
                params["k"] = p.rgb("k", (1.0,) * 3)
            else:
                params["eta"], params["k"] = None, None  # eta = 0, k = 1: a perfect mirror
            params["specular_reflectance"] = self.color_param(p, "specular_reflectance", (1.0,) * 3)
            if t == "roughconductor":
                self.read_microfacet(p, params)
        elif t in ("plastic", "roughplastic"):
            params["int_ior"] = lookup_ior(p, "int_ior", "polypropylene")
            params["ext_ior"] = lookup_ior(p, "ext_ior", "air")
            if params["int_ior"] == params["ext_ior"]:
                p.fail("int_ior and ext_ior must differ")
            params["diffuse_reflectance"] = self.color_param(p, "diffuse_reflectance", (0.5,) * 3)
            params["specular_reflectance"] = self.color_param(p, "specular_reflectance", (1.0,) * 3)
            params["nonlinear"] = p.bool("nonlinear", False)
            if t == "roughplastic":
                self.read_microfacet(p, params)
        elif t != "twosided":
            p.fail("bsdf '%s' is not supported (known: diffuse, twosided, dielectric, roughdielectric, "
                   "conductor, roughconductor, plastic, roughplastic)" % t)
        for k in p.textures:
            if k not in params:
                p.fail("<%s type=\"%s\"> does not take a texture '%s'" % (p.tag, t, k), k)
        p.finish()
        b = Bsdf(t, p.where + " (line %d)" % n.line, params, nested)
        self.register(n, "bsdf", b)
        return b

    def read_microfacet(self, p, params):
        dist = p.str("distribution", "beckmann")
        if dist not in ("beckmann", "ggx"):
            p.fail("distribution must be beckmann or ggx", "distribution")
        if p.has("alpha_u") or p.has("alpha_v"):
            p.fail("anisotropic roughness is not supported", "alpha_u")
        if "alpha" in p.textures:
            p.fail("textured alpha is not supported", "alpha")
        alpha = p.float("alpha", 0.1)
        if not alpha >= 0:
            p.fail("alpha must be >= 0", "alpha")
        p.ignore("sample_visible")  # a sampling choice: noise only
        params["distribution"], params["alpha"] = dist, alpha

    # -- shapes and emitters -----------------------------------------------------------------
    def read_radiance(self, p):
        if "radiance" in getattr(p, "textures", {}):
            p.fail("textured radiance is not supported", "radiance")
        return tuple(p.rgb("radiance", (1.0,) * 3))

    def read_shape(self, n):
        p = Plugin(n, "shape")
        t = p.type
        M = p.transform("to_world")
        flip = p.bool("flip_normals", False)
        where = p.where
        fail = lambda msg: p.fail(msg, "filename")
        if t == "obj":
            fname = p.str("filename")
            if not fname:
                p.fail("missing filename", "filename")
            full = os.path.normpath(os.path.join(self.dir, fname))
            face_normals = p.bool("face_normals", False)
            flip_tex = p.bool("flip_tex_coords", True)
            V, VT, VN, cv, ct, cn = read_obj(full, where, fail)
            normals = None
            if not face_normals:
                if len(VN):
                    if (cn < 0).any():
                        p.fail("%s: some face corners have normals and some do not" % full, "filename")
                    normals = VN[cn]
                # else: computed below from world-space positions
            uvs = None
            if len(VT):
                # Mitsuba flips v on load (flip_tex_coords, default true) because its bitmaps have
                # their origin at the top-left; Blender's images have it at the bottom-left. So with
                # the flip, Blender v = 1 - (1 - vt) = vt: the OBJ's vt as written; without, 1 - vt.
                # Corners without vt get Mitsuba's (0, 0).
                uvm = np.where((ct >= 0)[..., None], VT[np.maximum(ct, 0)], 0.0)
                if flip_tex:
                    uvm = np.where((ct >= 0)[..., None], uvm * [1, -1] + [0, 1], 0.0)
                uvs = np.stack([uvm[..., 0], 1.0 - uvm[..., 1]], axis=-1)
            mesh = finalize_mesh(V, cv, normals, uvs, M, flip, where)
            if not face_normals and not len(VN):
                # Mitsuba's vertices are keyed by (v, vt, vn); Mitsuba 3's
                # Mesh::recompute_vertex_normals weights unit face normals by the corner angle
                # (Thuermer & Wuethrich), in its scalar and JIT variants alike, not by area
                keep_keys = self._obj_keys(cv, ct, mesh, M, flip)
                mesh.normals = angle_weighted_normals(mesh.P, mesh.tris, keep_keys)
                note("%s: %s has no normals; computed Mitsuba 3's angle-weighted vertex normals" % (where, fname))
            source = fname
        elif t == "ply":
            fname = p.str("filename")
            if not fname:
                p.fail("missing filename", "filename")
            full = os.path.normpath(os.path.join(self.dir, fname))
            face_normals = p.bool("face_normals", False)
            V, N, UV, tris = read_ply(full, fail)
            normals = N[tris] if (N is not None and not face_normals) else None
            # Mitsuba's PLY loader does not flip v; Blender's image origin is bottom-left
            uvs = np.stack([UV[:, 0], 1.0 - UV[:, 1]], axis=1)[tris] if UV is not None else None
            mesh = finalize_mesh(V, tris, normals, uvs, M, flip, where)
            if N is None and not face_normals:
                mesh.normals = angle_weighted_normals(mesh.P, mesh.tris, mesh.tris)
            source = fname
        elif t in ("rectangle", "cube"):
            P, tris, normals, uvs = make_rectangle() if t == "rectangle" else make_cube()
            mesh = finalize_mesh(P, tris, normals, uvs, M, flip, where)
            source = t
        elif t == "sphere":
            c = p.point("center", np.zeros(3))
            r = p.float("radius", 1.0)
            if not r > 0:
                p.fail("radius must be > 0", "radius")
            full_m = M @ np.array([[r, 0, 0, c[0]], [0, r, 0, c[1]], [0, 0, r, c[2]], [0, 0, 0, 1.0]])
            sv = np.linalg.svd(full_m[:3, :3], compute_uv=False)
            if sv.max() - sv.min() > 1e-5 * sv.max():
                p.fail("a sphere's to_world must not scale anisotropically or shear", "to_world")
            if any(ch.tag == "emitter" for ch in p.children):
                segs = EMITTER_SPHERE_SEGMENTS
                P, tris, normals, uvs = make_sphere(segs, match_area=True)
                scale = float(np.linalg.norm(P[0]))  # every vertex sits at the pushed-out radius
                approximation("emitting sphere shapes are tessellated: %dx%d-segment UV sphere with exact "
                              "radial vertex normals, vertices at %.5f x radius so that its area is the "
                              "sphere's (faces within %.1e x radius of the true sphere; finer meshes lose "
                              "emitted light in Cycles 3.4)"
                              % (segs + (scale, max(scale - 1, 1 - scale * math.cos(math.pi / segs[1])))))
            else:
                P, tris, normals, uvs = make_sphere()
                approximation("sphere shapes are tessellated: %dx%d-segment UV sphere with exact radial "
                              "vertex normals (max distance to the true sphere %.1e x radius)"
                              % (SPHERE_SEGMENTS + (1 - math.cos(math.pi / SPHERE_SEGMENTS[1]),)))
            mesh = finalize_mesh(P, tris, normals, uvs, full_m, flip, where)
            source = "sphere"
        else:
            p.fail("shape '%s' is not supported (obj, ply, rectangle, cube, sphere)" % t)
        bsdf, emitter = None, None
        for c in p.children:
            if c.tag == "bsdf":
                if bsdf is not None:
                    c.fail("shape has more than one BSDF")
                bsdf = self.read_bsdf(c, where + ".bsdf")
            elif c.tag == "ref":
                kind, obj = self.resolve(c, ("bsdf", "medium"))
                if kind == "medium":
                    approximation("participating media are ignored (medium reference in %s)" % where)
                    continue
                if bsdf is not None:
                    c.fail("shape has more than one BSDF")
                bsdf = obj
            elif c.tag == "emitter":
                e = Plugin(c, where + ".emitter")
                if e.type != "area":
                    e.fail("a shape's emitter must be 'area', got '%s'" % e.type)
                if emitter is not None:
                    c.fail("shape has more than one emitter")
                e.textures = {}
                for cc in e.children:
                    if cc.tag == "texture":
                        cc.fail("textured radiance is not supported", "radiance")
                    cc.fail("unexpected <%s> in the area emitter" % cc.tag)
                emitter = self.read_radiance(e)
                e.finish()
                self.register(c, "emitter", None)
            elif c.tag == "medium":
                approximation("participating media are ignored (medium in %s)" % where)
            else:
                c.fail("unexpected <%s> inside the shape" % c.tag)
        if bsdf is None:
            bsdf = self.default_bsdf()
        p.finish()
        self.register(n, "shape", None)
        self.scene.shapes.append({"id": p.id or "shape_%d" % len(self.scene.shapes), "mesh": mesh,
                                  "bsdf": bsdf, "emitter": emitter, "where": where, "source": source})

    def _obj_keys(self, cv, ct, mesh, M, flip):
        """Mitsuba vertex ids (by (v, vt) key) for the triangles kept by finalize_mesh, in the
        final winding. Recomputed the same way finalize_mesh orders and filters."""
        det = np.linalg.det(M[:3, :3])
        rev = (det < 0) != flip
        key = cv * (ct.max() + 2) + (ct + 1)
        if rev:
            key, cvv = key[:, ::-1], cv[:, ::-1]
        else:
            cvv = cv
        p = mesh.P[cvv]
        area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        keep = (area2 > 0) & (cvv[:, 0] != cvv[:, 1]) & (cvv[:, 1] != cvv[:, 2]) & (cvv[:, 0] != cvv[:, 2])
        _, inv = np.unique(key[keep].ravel(), return_inverse=True)
        return inv.reshape(-1, 3)

    def default_bsdf(self):
        if "__default__" not in self.ids:
            self.ids["__default__"] = ("bsdf", Bsdf("diffuse", "default bsdf", {"reflectance": (0.5,) * 3}, []))
        return self.ids["__default__"][1]

    def read_env(self, n):
        p = Plugin(n, "emitter")
        if p.type == "area":
            p.fail("an 'area' emitter must be inside a <shape>")
        if self.scene.env is not None:
            p.fail("only one environment emitter (constant or envmap) is supported")
        for c in p.children:
            c.fail("unexpected <%s> inside the emitter" % c.tag)
        if p.type == "constant":
            p.textures = {}
            self.scene.env = ("constant", self.read_radiance(p))
        elif p.type == "envmap":
            fname = p.str("filename")
            if not fname:
                p.fail("missing filename", "filename")
            full = os.path.normpath(os.path.join(self.dir, fname))
            if not os.path.isfile(full):
                p.fail("environment map not found: %s" % full, "filename")
            M = p.transform("to_world")
            R = M[:3, :3]
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-5) or np.linalg.det(R) < 0:
                p.fail("envmap to_world must be a rotation", "to_world")
            p.ignore("mis_compensation")  # a sampling choice
            self.scene.env = ("envmap", full, p.float("scale", 1.0), M)
        else:
            p.fail("emitter '%s' is not supported (area inside a shape, constant, envmap)" % p.type)
        p.finish()
        self.register(n, "emitter", None)


# --------------------------------------------------------------------------------------------
# Shader node graphs
# --------------------------------------------------------------------------------------------

class Graph:
    """Helper for building Cycles node graphs. A value is a Python float (folded in Python) or a
    node output socket; a colour is a list of 3 values."""

    def __init__(self, nt):
        self.nt = nt
        self.count = 0
        self._geometry = None

    def node(self, kind, **props):
        n = self.nt.nodes.new(kind)
        for k, v in props.items():
            setattr(n, k, v)
        self.count += 1
        n.location = (-200 * (self.count // 40), -120 * (self.count % 40))
        return n

    def set_input(self, sock, v):
        if isinstance(v, (int, float)):
            sock.default_value = float(v)
        elif isinstance(v, tuple):
            sock.default_value = tuple(v) + ((1.0,) if len(v) == 3 and len(sock.default_value) == 4 else ())
        else:
            self.nt.links.new(v, sock)

    def math(self, op, a, b=None):
        if isinstance(a, (int, float)) and (b is None or isinstance(b, (int, float))):
            a = float(a)
            if op == "ADD":
                return a + b
            if op == "SUBTRACT":
                return a - b
            if op == "MULTIPLY":
                return a * b
            if op == "DIVIDE":
                return a / b if b != 0 else 0.0
            if op == "SQRT":
                return math.sqrt(a) if a > 0 else 0.0
            if op == "ABSOLUTE":
                return abs(a)
            if op == "MINIMUM":
                return min(a, b)
            if op == "MAXIMUM":
                return max(a, b)
            raise ValueError(op)
        n = self.node("ShaderNodeMath", operation=op, use_clamp=False)
        self.set_input(n.inputs[0], a)
        if b is not None:
            self.set_input(n.inputs[1], b)
        return n.outputs[0]

    def add(self, a, b):
        if isinstance(b, (int, float)) and b == 0:
            return a
        if isinstance(a, (int, float)) and a == 0:
            return b
        return self.math("ADD", a, b)

    def sub(self, a, b):
        return self.math("SUBTRACT", a, b)

    def mul(self, a, b):
        for x, y in ((a, b), (b, a)):
            if isinstance(x, (int, float)) and x == 1:
                return y
            if isinstance(x, (int, float)) and x == 0:
                return 0.0
        return self.math("MULTIPLY", a, b)

    def div(self, a, b):
        if isinstance(b, (int, float)) and b == 1:
            return a
        return self.math("DIVIDE", a, b)

    def sqrt(self, a):
        return self.math("SQRT", a)

    def geometry(self):
        if self._geometry is None:
            self._geometry = self.node("ShaderNodeNewGeometry")
        return self._geometry

    def backfacing(self):
        return self.geometry().outputs["Backfacing"]

    def cos_incident(self):
        """cos(theta_i) = |N . I| with N the shading normal (Cycles faces it to the viewer) and I the
        direction to the viewer, clamped to [0, 1]."""
        if not hasattr(self, "_cos"):
            g = self.geometry()
            d = self.node("ShaderNodeVectorMath", operation="DOT_PRODUCT")
            self.nt.links.new(g.outputs["Normal"], d.inputs[0])
            self.nt.links.new(g.outputs["Incoming"], d.inputs[1])
            self._cos = self.math("MINIMUM", self.math("ABSOLUTE", d.outputs["Value"]), 1.0)
        return self._cos

    def color(self, vals):
        """A colour input value: a tuple when constant, else a Combine Color socket."""
        if all(isinstance(v, (int, float)) for v in vals):
            return tuple(float(v) for v in vals)
        n = self.node("ShaderNodeCombineColor")
        n.mode = "RGB"
        for i, v in enumerate(vals):
            self.set_input(n.inputs[i], v)
        return n.outputs[0]

    def channels(self, c):
        """A colour (tuple or socket) as 3 values."""
        if isinstance(c, tuple):
            return [float(x) for x in c]
        n = self.node("ShaderNodeSeparateColor")
        n.mode = "RGB"
        self.nt.links.new(c, n.inputs[0])
        return [n.outputs[0], n.outputs[1], n.outputs[2]]

    def curve(self, x, xs, ys):
        """Piecewise-linear y(x) through the points (a Float Curve with vector handles; Cycles bakes
        it into a 256-entry table over [0, 1] and interpolates linearly)."""
        n = self.node("ShaderNodeFloatCurve")
        m = n.mapping
        m.use_clip = False
        c = m.curves[0]
        pts = c.points
        while len(pts) > 2:
            pts.remove(pts[-1])
        pts[0].location = (float(xs[0]), float(ys[0]))
        pts[1].location = (float(xs[-1]), float(ys[-1]))
        for xv, yv in zip(xs[1:-1], ys[1:-1]):
            pts.new(float(xv), float(yv))
        for pt in pts:
            pt.handle_type = "VECTOR"
        m.update()
        n.inputs["Factor"].default_value = 1.0
        self.set_input(n.inputs["Value"], x)
        return n.outputs[0]


def conductor_fresnel(g, cos_i, eta, k):
    """Exact unpolarised Fresnel reflectance of a conductor (Mitsuba 3's fresnel_conductor, after
    K. D. Moeller, Optics), for one channel with relative IOR eta + i k:
        s2 = 1 - c^2,  t1 = eta^2 - k^2 - s2
        a^2 + b^2 = sqrt(t1^2 + 4 eta^2 k^2),  a = sqrt((a^2 + b^2 + t1) / 2)
        Rs = (a^2 + b^2 + c^2 - 2 a c) / (a^2 + b^2 + c^2 + 2 a c)
        Rp = Rs (c^2 (a^2 + b^2) + s2^2 - 2 a c s2) / (c^2 (a^2 + b^2) + s2^2 + 2 a c s2)
        F = (Rs + Rp) / 2
    With k = 0 it is the dielectric Fresnel reflectance (total internal reflection included)."""
    c2 = g.mul(cos_i, cos_i)
    s2 = g.sub(1.0, c2)
    s4 = g.mul(s2, s2)
    t1 = g.sub(eta * eta - k * k, s2)
    a2pb2 = g.sqrt(g.add(g.mul(t1, t1), 4.0 * eta * eta * k * k))
    a = g.sqrt(g.mul(0.5, g.add(a2pb2, t1)))
    term1 = g.add(a2pb2, c2)
    term2 = g.mul(g.mul(2.0, cos_i), a)
    rs = g.div(g.sub(term1, term2), g.add(term1, term2))
    term3 = g.add(g.mul(a2pb2, c2), s4)
    term4 = g.mul(term2, s2)
    rp = g.mul(rs, g.div(g.sub(term3, term4), g.add(term3, term4)))
    return g.mul(0.5, g.add(rs, rp))


class MaterialBuilder:
    def __init__(self, max_depth):
        self.max_depth = max_depth
        self.cache = {}
        self.images = {}
        self.one_sided = False

    def image_node(self, g, tex):
        img = self.images.get(tex.filename)
        if img is None:
            try:
                img = bpy.data.images.load(tex.filename, check_existing=False)
            except RuntimeError as e:
                raise SceneError("cannot load texture: %s" % e, None, None, tex.where)
            # Mitsuba: 8-bit images are sRGB-encoded unless raw=true; float images are linear
            if tex.raw or img.is_float:
                img.colorspace_settings.name = "Non-Color"
            else:
                img.colorspace_settings.name = "sRGB"
            img.alpha_mode = "NONE"
            self.images[tex.filename] = img
        n = g.node("ShaderNodeTexImage")
        n.image = img
        n.interpolation = "Linear" if tex.filter_type == "bilinear" else "Closest"
        n.extension = "REPEAT" if tex.wrap == "repeat" else "EXTEND"
        n.projection = "FLAT"
        uv = g.node("ShaderNodeUVMap")
        g.nt.links.new(uv.outputs["UV"], n.inputs["Vector"])
        return n.outputs["Color"]

    def color_input(self, g, v):
        return self.image_node(g, v) if isinstance(v, Texture) else tuple(v)

    def black(self, g):
        n = g.node("ShaderNodeBsdfDiffuse")
        n.inputs["Color"].default_value = (0, 0, 0, 1)
        return n.outputs[0]

    def mix_backfacing(self, g, front, back):
        m = g.node("ShaderNodeMixShader")
        g.nt.links.new(g.backfacing(), m.inputs["Fac"])
        g.nt.links.new(front, m.inputs[1])
        g.nt.links.new(back, m.inputs[2])
        return m.outputs[0]

    def shader(self, g, b, one_sided=True):
        """The closure socket for BSDF b. Mitsuba's non-transmissive BSDFs are one-sided (black
        from the back) unless wrapped in twosided: gate them with Geometry.Backfacing."""
        t, prm = b.type, b.params
        if t == "twosided":
            front = self.shader(g, b.nested[0], one_sided=False)
            if len(b.nested) == 1:
                return front
            return self.mix_backfacing(g, front, self.shader(g, b.nested[1], one_sided=False))
        if t in ("dielectric", "roughdielectric"):
            n = g.node("ShaderNodeBsdfGlass")
            n.inputs["IOR"].default_value = prm["int_ior"] / prm["ext_ior"]  # Cycles inverts it on backfaces
            n.inputs["Color"].default_value = tuple(prm["color"]) + (1.0,)
            if t == "dielectric":
                n.distribution = "SHARP"
            else:
                n.distribution = prm["distribution"].upper()
                n.inputs["Roughness"].default_value = math.sqrt(prm["alpha"])
                approximation("%s: roughdielectric as Cycles' microfacet Glass BSDF (%s, roughness = sqrt(alpha)); "
                              "Cycles and Mitsuba use the same Walter et al. model but this translation is "
                              "not verified numerically" % (b.where, prm["distribution"]))
            approximation("%s: Cycles' glass does not scale refracted radiance by 1/eta^2 as Mitsuba does; "
                          "identical for paths that leave the glass again (closed objects with no light or "
                          "other surface inside), different otherwise" % b.where)
            return n.outputs[0]
        if t == "diffuse":
            n = g.node("ShaderNodeBsdfDiffuse")
            n.inputs["Roughness"].default_value = 0.0
            g.set_input(n.inputs["Color"], self.color_input(g, prm["reflectance"]))
            out = n.outputs[0]
        elif t in ("conductor", "roughconductor"):
            out = self.conductor(g, b)
        elif t in ("plastic", "roughplastic"):
            out = self.plastic(g, b)
        else:
            raise SceneError("internal: unhandled bsdf %s" % t)
        if not one_sided:
            return out
        self.one_sided = True
        return self.mix_backfacing(g, out, self.black(g))

    def glossy(self, g, prm, color):
        n = g.node("ShaderNodeBsdfGlossy")
        alpha = prm.get("alpha")
        if alpha is None or alpha == 0:
            n.distribution = "SHARP"
        else:
            # Cycles squares the Roughness input to get the microfacet alpha (svm_closure.h:
            # "float roughness = sqr(param1); bsdf->alpha_x = roughness"), so roughness = sqrt(alpha).
            n.distribution = prm["distribution"].upper()
            n.inputs["Roughness"].default_value = math.sqrt(alpha)
        g.set_input(n.inputs["Color"], color)
        return n.outputs[0]

    def conductor(self, g, b):
        prm = b.params
        spec = prm["specular_reflectance"]
        spec_c = g.channels(self.color_input(g, spec)) if isinstance(spec, Texture) else [float(x) for x in spec]
        if prm["eta"] is None:
            F = [1.0, 1.0, 1.0]  # eta = 0, k = 1: F = 1 at every angle
        else:
            cos_i = g.cos_incident()
            F = [conductor_fresnel(g, cos_i, prm["eta"][i], prm["k"][i]) for i in range(3)]
        color = g.color([g.mul(F[i], spec_c[i]) for i in range(3)])
        if b.type == "roughconductor" and prm["eta"] is not None and prm["alpha"] > 0:
            approximation("%s: roughconductor: Cycles 3.4 has no complex-IOR Fresnel; the exact conductor "
                          "Fresnel is evaluated at the macro-surface normal (cos = |N.I|) and multiplies a "
                          "Fresnel-free %s Glossy BSDF with roughness sqrt(alpha) = %.4g; Mitsuba evaluates it "
                          "at each microfacet normal" % (b.where, prm["distribution"], math.sqrt(prm["alpha"])))
        return self.glossy(g, prm, color)

    def plastic(self, g, b):
        """Mitsuba 3's plastic / roughplastic:
            f = spec * F-term  +  d / (1 - (nonlinear ? d F_int : F_int)) / (pi eta^2) * t(cos_i) * t(cos_o)
        with t = 1 - F (smooth) or the rough interface's transmittance table (rough). Cycles'
        closures cannot see cos_o (the light side), so t(cos_o) is replaced by its cosine-weighted
        hemispherical mean (exact for the energy under uniform illumination); everything else that
        depends on cos_i is evaluated per shading point from |N.I|."""
        prm = b.params
        eta = prm["int_ior"] / prm["ext_ior"]
        rough = b.type == "roughplastic" and prm["alpha"] > 0
        cos_i = g.cos_incident()
        dif = prm["diffuse_reflectance"]
        dif_c = g.channels(self.color_input(g, dif)) if isinstance(dif, Texture) else [float(x) for x in dif]
        spec = prm["specular_reflectance"]
        spec_c = g.channels(self.color_input(g, spec)) if isinstance(spec, Texture) else [float(x) for x in spec]
        if rough:
            tab = rough_tables(prm["distribution"], prm["alpha"], eta)
            f_int = tab["internal"]
            t_table = tab["T"]
            t_i = g.curve(cos_i, tab["mu"], t_table)
            t_o_mean = cosine_mean(lambda mu: mitsuba_lerp(t_table, mu))
            # specular lobe: Cycles' Fresnel-free microfacet Glossy (same D, G) scaled per cos_i so
            # that its albedo equals Mitsuba's R(cos_i) (Fresnel inside the integral)
            ratio = np.where(tab["A"] > 1e-6, tab["R"] / np.maximum(tab["A"], 1e-6), 0.0)
            ratio[0] = ratio[1]
            s_i = g.curve(cos_i, tab["mu"], ratio)
            approximation("%s: roughplastic (%s, alpha %.4g, eta %.4g): diffuse term's t(cos_o) replaced "
                          "by its cosine-weighted mean %.5f; the specular lobe is a Fresnel-free Cycles %s Glossy "
                          "(roughness sqrt(alpha)) scaled by R(cos_i)/A(cos_i) so its albedo matches Mitsuba's "
                          "(tables integrated numerically here: internal reflectance %.5f)"
                          % (b.where, prm["distribution"], prm["alpha"], eta, t_o_mean,
                             prm["distribution"].upper(), f_int))
        else:
            f_int = fresnel_diffuse_reflectance(1.0 / eta)
            F = conductor_fresnel(g, cos_i, eta, 0.0)
            t_i = g.sub(1.0, F)
            s_i = F
            t_o_mean = 1.0 - cosine_mean(lambda mu: fresnel_dielectric_np(mu, eta)[0])
            approximation("%s: plastic (eta %.4g): diffuse term's (1 - F(cos_o)) replaced by its "
                          "cosine-weighted mean %.5f; the specular part (F(cos_i) mirror) is exact"
                          % (b.where, eta, t_o_mean))
        if prm["nonlinear"]:
            d_eff = [g.div(dif_c[i], g.sub(1.0, g.mul(dif_c[i], f_int))) for i in range(3)]
        else:
            d_eff = [g.div(dif_c[i], 1.0 - f_int) for i in range(3)]
        scale = g.mul(t_i, t_o_mean / (eta * eta))
        dn = g.node("ShaderNodeBsdfDiffuse")
        dn.inputs["Roughness"].default_value = 0.0
        g.set_input(dn.inputs["Color"], g.color([g.mul(d_eff[i], scale) for i in range(3)]))
        gl = self.glossy(g, prm if rough else {}, g.color([g.mul(spec_c[i], s_i) for i in range(3)]))
        add = g.node("ShaderNodeAddShader")
        g.nt.links.new(dn.outputs[0], add.inputs[0])
        g.nt.links.new(gl, add.inputs[1])
        return add.outputs[0]

    def material(self, bsdf, radiance):
        key = (id(bsdf), radiance)
        if key in self.cache:
            return self.cache[key]
        mat = bpy.data.materials.new(name=(bsdf.where.split(" (")[0] + (" +emitter" if radiance else ""))[:60])
        mat.use_nodes = True
        nt = mat.node_tree
        for n in list(nt.nodes):
            nt.nodes.remove(n)
        g = Graph(nt)
        outn = g.node("ShaderNodeOutputMaterial")
        outn.target = "CYCLES"
        if self.max_depth == 1:
            # Only emitters seen directly: no BSDF at all, so no path continues and next-event
            # estimation at the first hit adds nothing. Exact.
            surface = None
        else:
            surface = self.shader(g, bsdf)
        if radiance is not None:
            em = g.node("ShaderNodeEmission")
            em.inputs["Color"].default_value = tuple(radiance) + (1.0,)
            # Mitsuba's area lights emit on the front (+normal) side only
            g.set_input(em.inputs["Strength"], g.sub(1.0, g.backfacing()))
            if surface is None:
                surface = em.outputs[0]
            else:
                add = g.node("ShaderNodeAddShader")
                nt.links.new(surface, add.inputs[0])
                nt.links.new(em.outputs[0], add.inputs[1])
                surface = add.outputs[0]
        if surface is None:
            surface = self.black(g)
        nt.links.new(surface, outn.inputs["Surface"])
        mat.cycles.sample_as_light = True
        self.cache[key] = mat
        return mat


# --------------------------------------------------------------------------------------------
# Blender scene
# --------------------------------------------------------------------------------------------

def filter_variance_width(kind, param):
    """Cycles' Gaussian filter (film.cpp): f(v) = exp(-2 (6 v / (3 w))^2) = exp(-8 v^2 / w^2) over
    |v| <= 1.5 w, i.e. sigma = w / 4 (truncated at 6 sigma), w = filter_width in pixels, applied
    separably per axis as Mitsuba's filters are. Return the width whose variance matches Mitsuba's
    filter: tent of radius r (variance r^2 / 6), or Mitsuba's gaussian (stddev s, cut at 4 s with
    the value at the cut subtracted)."""
    if kind == "tent":
        var = param * param / 6.0
    else:
        s = param
        x = np.linspace(-4 * s, 4 * s, 200001)
        f = np.maximum(np.exp(-x * x / (2 * s * s)) - math.exp(-8.0), 0)
        var = float((f * x * x).sum() / f.sum())
    return 4.0 * math.sqrt(var), var


NORMAL_ERRORS = []  # per-loop angle (degrees) between the wanted and the stored custom normal


def build_mesh_object(name, mesh, mat):
    P, tris = mesh.P, mesh.tris
    nt, nv = len(tris), len(P)
    me = bpy.data.meshes.new(name)
    me.vertices.add(nv)
    me.vertices.foreach_set("co", P.astype(np.float32).ravel())
    me.loops.add(3 * nt)
    me.loops.foreach_set("vertex_index", tris.astype(np.int32).ravel())
    me.polygons.add(nt)
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * nt, 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(nt, 3, dtype=np.int32))
    smooth = mesh.normals is not None
    me.polygons.foreach_set("use_smooth", np.full(nt, smooth, dtype=bool))
    if mesh.uvs is not None:
        uvl = me.uv_layers.new(name="UVMap")
        uvl.data.foreach_set("uv", mesh.uvs.astype(np.float32).ravel())
    me.update(calc_edges=True)
    if smooth:
        # The file's (or Mitsuba's computed) per-vertex normals as custom split normals
        me.use_auto_smooth = True
        me.auto_smooth_angle = math.pi
        want = mesh.normals.reshape(-1, 3).astype(np.float32)
        me.normals_split_custom_set(want)
        # Blender stores custom normals compressed and merges nearly equal ones within a smooth
        # fan: measure what Cycles will get
        me.calc_normals_split()
        got = np.zeros(3 * len(me.loops), dtype=np.float32)
        me.loops.foreach_get("normal", got)
        cosang = (got.reshape(-1, 3) * want).sum(1) / np.maximum(np.linalg.norm(want, axis=1), 1e-30)
        NORMAL_ERRORS.append(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))))
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    ob.cycles.shadow_terminator_offset = 0.0
    ob.cycles.shadow_terminator_geometry_offset = 0.0  # default 0.1 moves shadow-ray origins: bias
    return ob


def setup_world(scene_desc, world):
    world.use_nodes = True
    nt = world.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    g = Graph(nt)
    out = g.node("ShaderNodeOutputWorld")
    bg = g.node("ShaderNodeBackground")
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    env = scene_desc.env
    if env is None:
        # Blender's default world is grey; Mitsuba's is black
        bg.inputs["Color"].default_value = (0, 0, 0, 1)
        bg.inputs["Strength"].default_value = 0.0
        world.cycles.sampling_method = "NONE"
        return {"type": "none (black)"}
    if env[0] == "constant":
        bg.inputs["Color"].default_value = tuple(env[1]) + (1.0,)
        bg.inputs["Strength"].default_value = 1.0
        world.cycles.sampling_method = "AUTOMATIC"
        return {"type": "constant", "radiance": list(env[1])}
    _, fname, scale, M = env
    img = bpy.data.images.load(fname, check_existing=False)
    img.colorspace_settings.name = "Non-Color" if img.is_float else "sRGB"
    W, H = img.size
    # Mitsuba 3 (envmap.cpp): d = to_world^-1 w (w: the direction away from the scene),
    #   u = atan2(d.x, -d.z) / 2pi,  v = acos(d.y) / pi,  v = 0 at the file's top row;
    #   texel x = u W - 0.5 (periodic), row (from the top) y = v (H - 1): rows sit on the poles.
    # Cycles (kernel/camera/projection.h, svm_node_tex_environment): the world's Generated
    #   coordinate is the ray direction b (away from the scene), and
    #   u = 0.5 - atan2(b.y, b.x) / 2pi,  v = 1 - acos(b.z) / pi,  v = 0 at the bottom row,
    #   texel x = u W - 0.5, row from the top = acos(b.z) / pi * H - 0.5.
    # Matching u: (b.x, b.y) along (d.z, d.x). Matching rows: theta_b = (theta_m (H-1) + pi/2) / H
    #   with theta_m = acos(d.y). So b = (sin theta_b d.z / r, sin theta_b d.x / r, cos theta_b),
    #   r = hypot(d.x, d.z).
    Rinv = M[:3, :3].T
    tc = g.node("ShaderNodeTexCoord")
    gen = tc.outputs["Generated"]

    def dot_row(row):
        n = g.node("ShaderNodeVectorMath", operation="DOT_PRODUCT")
        n.inputs[1].default_value = tuple(float(x) for x in row)
        nt.links.new(gen, n.inputs[0])
        return n.outputs["Value"]

    dx, dy, dz = (dot_row(Rinv[i]) for i in range(3))
    nrm = g.node("ShaderNodeVectorMath", operation="LENGTH")
    nt.links.new(gen, nrm.inputs[0])
    length = nrm.outputs["Value"]
    cy = g.math("MINIMUM", g.math("MAXIMUM", g.div(dy, length), -1.0), 1.0)
    th_m = g.math("ARCCOSINE", cy)
    th_b = g.mul(g.add(g.mul(th_m, float(H - 1)), math.pi / 2), 1.0 / H)
    r = g.sqrt(g.add(g.mul(dx, dx), g.mul(dz, dz)))
    sth = g.math("SINE", th_b)
    bx = g.mul(sth, g.div(dz, r))
    by = g.mul(sth, g.div(dx, r))
    bz = g.math("COSINE", th_b)
    comb = g.node("ShaderNodeCombineXYZ")
    for i, v in enumerate((bx, by, bz)):
        g.set_input(comb.inputs[i], v)
    et = g.node("ShaderNodeTexEnvironment")
    et.image = img
    et.interpolation = "Linear"
    et.projection = "EQUIRECTANGULAR"
    nt.links.new(comb.outputs[0], et.inputs["Vector"])
    nt.links.new(et.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = scale
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = max(64, min(4096, W))
    return {"type": "envmap", "file": fname, "scale": scale, "size": [W, H]}


def without_light_sampling(materials, world):
    """--strategy bsdf: emission is found only by BSDF-sampled rays (no next-event estimation, no
    MIS weights), like `latentpt render --strategy bsdf`."""
    for mat in materials:
        mat.cycles.sample_as_light = False
    world.cycles.sampling_method = "NONE"
    note("--strategy bsdf: light sampling off (materials' sample_as_light and the world's sampling)")


def setup_camera(sensor, width, height):
    M = np.array(sensor["to_world"], dtype=np.float64)
    R = M[:3, :3]
    U, S, Vt = np.linalg.svd(R)
    if np.abs(S - 1).max() > 1e-3:
        raise SceneError("camera to_world must not scale or shear (Mitsuba rejects it); singular values %s"
                         % np.round(S, 5), sensor["node"].file, sensor["node"].line, sensor["where"] + ".to_world")
    if np.linalg.det(R) < 0:
        raise SceneError("a mirrored camera to_world (det < 0) is not supported", sensor["node"].file,
                         sensor["node"].line, sensor["where"] + ".to_world")
    Rn = U @ Vt  # the nearest rotation: removes rounding-level scale/shear from the file's digits
    B = np.eye(4)
    B[:3, :3] = Rn @ np.diag([-1.0, 1.0, -1.0])
    B[:3, 3] = M[:3, 3]
    cam = bpy.data.cameras.new("camera")
    cam.type = "PERSP"
    cam.shift_x = cam.shift_y = 0.0
    cam.dof.use_dof = False
    cam.clip_start = sensor["near"]
    cam.clip_end = sensor["far"]
    fov = math.radians(sensor["fov"])
    axis = sensor["fov_axis"]
    aspect = width / height
    if axis == "smaller":
        axis = "y" if aspect > 1 else "x"
    elif axis == "larger":
        axis = "x" if aspect > 1 else "y"
    elif axis == "diagonal":
        fov = 2 * math.atan(math.tan(fov / 2) * width / math.hypot(width, height))
        axis = "x"
    if axis == "x":
        cam.sensor_fit = "HORIZONTAL"
        cam.sensor_width = 36.0
        cam.lens = 18.0 / math.tan(fov / 2)
    else:
        cam.sensor_fit = "VERTICAL"
        cam.sensor_height = 24.0
        cam.lens = 12.0 / math.tan(fov / 2)
    ob = bpy.data.objects.new("camera", cam)
    bpy.context.scene.collection.objects.link(ob)
    ob.matrix_world = Matrix(B.tolist())
    bpy.context.scene.camera = ob
    return {"fov_deg": sensor["fov"], "fov_axis": sensor["fov_axis"], "effective_axis": axis,
            "effective_fov_deg": math.degrees(fov), "near_clip": sensor["near"], "far_clip": sensor["far"],
            "blender_matrix": B.tolist()}


def configure_render(sc, args, width, height, spp, bounces, film_filter):
    r = sc.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y = width, height
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.film_transparent = False
    r.use_motion_blur = False
    r.use_compositing = False
    r.use_sequencer = False
    r.dither_intensity = 0.0
    r.threads_mode = "FIXED"
    r.threads = args["threads"]
    r.use_persistent_data = False
    cy = sc.cycles
    cy.device = "CPU"
    cy.feature_set = "SUPPORTED"
    cy.samples = spp
    cy.use_adaptive_sampling = False
    pattern = SAMPLING_PATTERNS[args["pattern"]]
    known = [i.identifier for i in cy.bl_rna.properties["sampling_pattern"].enum_items]
    if pattern not in known:  # the names changed after Blender 3.4
        raise SceneError("--pattern %s: this Blender's Cycles has no '%s' sampling pattern (it has %s)"
                         % (args["pattern"], pattern, ", ".join(known)))
    cy.sampling_pattern = pattern
    if args["pattern"] == "pmj":
        approximation("progressive multi-jittered samples (--pattern pmj) bias Cycles 3.4's direct light from a "
                      "tessellated (16 k-triangle) sphere light at low sample counts, by up to ~0.7 % of either sign "
                      "with the geometry: dining-room +0.65 % at 64-256 spp, +0.2 % at 512, none at 1024-2048 "
                      "(closed form, docs/validation.md); --pattern sobol showed none")
    cy.use_denoising = False
    cy.use_preview_denoising = False
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0  # default 10: biased
    cy.blur_glossy = 0.0            # "filter glossy": biased
    cy.light_sampling_threshold = 0.0
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.seed = args["seed"]
    cy.use_animated_seed = False
    cy.film_exposure = 1.0
    cy.max_bounces = bounces
    cy.diffuse_bounces = bounces
    cy.glossy_bounces = bounces
    cy.transmission_bounces = bounces
    cy.volume_bounces = bounces
    cy.transparent_max_bounces = bounces
    # Cycles starts its roulette after min_light_bounces; Mitsuba after rr_depth. Kept at 0 (the
    # roulette changes noise only, were it unbiased: Cycles 3.4's is not, see --no-roulette).
    cy.min_light_bounces = 0 if args["roulette"] else bounces + 1
    cy.min_transparent_bounces = 0
    cy.use_layer_samples = "IGNORE"
    cy.time_limit = 0.0
    cy.texture_limit_render = "OFF"  # never downscale textures
    cy.use_fast_gi = False
    cy.ao_bounces_render = 0
    r.use_simplify = False
    cy.pixel_filter_type = film_filter[0]
    cy.filter_width = film_filter[1]
    for k, v in (("use_guiding", False), ("auto_scrambling_distance", False), ("scrambling_distance", 1.0),
                 ("use_light_tree", False), ("preview_pause", False)):
        if hasattr(cy, k):
            setattr(cy, k, v)
    for vl in sc.view_layers:
        if hasattr(vl, "cycles") and hasattr(vl.cycles, "use_denoising"):
            vl.cycles.use_denoising = False
        vl.use_pass_combined = True
    vs = sc.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    vs.use_curve_mapping = False
    sc.display_settings.display_device = "sRGB"
    im = r.image_settings
    im.file_format = "OPEN_EXR"
    im.color_mode = "RGB"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    if hasattr(im, "color_management"):
        im.color_management = "FOLLOW_SCENE"
    r.use_file_extension = False
    r.use_overwrite = True
    return {"samples": spp, "seed": args["seed"], "strategy": args["strategy"], "roulette": args["roulette"], "threads": args["threads"], "device": "CPU",
            "sampling_pattern": cy.sampling_pattern, "max_bounces": bounces,
            "pixel_filter": film_filter[0], "filter_width_px": film_filter[1],
            "clamp_direct": 0.0, "clamp_indirect": 0.0, "filter_glossy": 0.0,
            "light_sampling_threshold": 0.0, "adaptive_sampling": False, "denoising": False,
            "view_transform": vs.view_transform, "exr": "float32 RGB, linear"}


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        args = parse_args(argv)
    except SystemExit as e:
        print(e, file=sys.stderr)
        hard_exit(2)
    if args is None:
        print(USAGE)
        hard_exit(0)
    if bpy is None:
        print("error: run this inside Blender: blender -b --factory-startup --python %s -- ..." % sys.argv[0],
              file=sys.stderr)
        hard_exit(2)

    t_start = time.time()
    scene_path = os.path.abspath(args["scene"])
    out_path = os.path.abspath(args["out"])
    log("scene %s" % scene_path)
    root = parse_xml(scene_path)
    params = substitute(root, args["defines"])
    desc = Loader(scene_path).load(root)

    width, height = desc.film["width"], desc.film["height"]
    if args["res"]:
        width, height = args["res"]
    spp = args["spp"] or desc.spp
    max_depth = desc.integrator["max_depth"] if args["max_depth"] is None else args["max_depth"]
    if max_depth == 0:
        raise SceneError("max_depth 0 renders nothing", scene_path, None, "integrator.max_depth")
    # Mitsuba's max_depth counts path segments; Cycles' max_bounces counts bounces after the
    # first hit: max_depth 2 (direct lighting) = 0 bounces. max_depth 1 is done with
    # emission-only materials (see MaterialBuilder.material).
    bounces = 1024 if max_depth < 0 else max(0, max_depth - 2)
    if max_depth > 0 and max_depth - 2 > 1024:
        bounces = 1024
    note("sampler '%s' ignored: Cycles draws its own samples (changes noise only, not the expected "
         "image)" % desc.sampler)
    if args["roulette"]:
        approximation("Russian roulette (Mitsuba rr_depth %d; Cycles from the first bounce) loses energy in "
                      "Cycles 3.4: in a closed diffuse box of albedo 0.9, BSDF sampling only, -0.02 %% at 4096 spp with "
                      "either pattern, -0.085 %% at 256 spp with pmj; exact without it "
                      "(docs/validation.md, 'A furnace'; --no-roulette turns it off)" % desc.integrator["rr_depth"])

    kind, prm = desc.film["filter"]
    if kind == "box":
        film_filter = ("BOX", 2.0 * prm)  # Mitsuba box radius 0.5 px = Cycles box width 1 px: exact
    else:
        w, var = filter_variance_width(kind, prm)
        film_filter = ("GAUSSIAN", w)
        approximation("rfilter %s (%s %g px) has no Cycles equivalent: Cycles' Gaussian with filter_width "
                      "%.5f px (sigma %.5f px) matches its variance %.5f px^2 per axis"
                      % (kind, "radius" if kind == "tent" else "stddev", prm, w, w / 4, var))

    # -- Blender scene ---------------------------------------------------------------------------
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    world = bpy.data.worlds.new("world")
    sc.world = world
    env_info = setup_world(desc, world)
    cam_info = setup_camera(desc.sensor, width, height)
    mb = MaterialBuilder(max_depth)
    ntri = 0
    for i, s in enumerate(desc.shapes):
        if s["mesh"].uvs is None and _uses_texture(s["bsdf"]):
            raise SceneError("%s: a textured BSDF on a mesh without texture coordinates is not supported"
                             % s["where"], scene_path)
        mat = mb.material(s["bsdf"], s["emitter"])
        build_mesh_object(("%03d_%s" % (i, s["id"]))[:60], s["mesh"], mat)
        ntri += len(s["mesh"].tris)
    if NORMAL_ERRORS:
        err = np.concatenate(NORMAL_ERRORS)
        (approximation if err.max() > 0 else note)("smooth shading: per-vertex normals become Blender custom split normals, which Blender "
                      "stores compressed (and merges when nearly equal within a smooth fan): measured deviation "
                      "from the wanted normals over %d corners: median %.1e deg, 99%% %.1e deg, max %.1e deg"
                      % (len(err), np.median(err), np.percentile(err, 99), err.max()))
    if mb.one_sided:
        note("one-sided Mitsuba BSDFs (not in twosided) are black from the back: gated with Geometry.Backfacing, "
             "which Cycles computes from the geometric normal (Mitsuba uses the shading frame)")
    log("%d shapes, %d triangles, %d materials" % (len(desc.shapes), ntri, len(mb.cache)))
    if args["strategy"] == "bsdf":
        without_light_sampling(bpy.data.materials, world)
    settings = configure_render(sc, args, width, height, spp, bounces, film_filter)
    settings.update({"mitsuba_max_depth": max_depth, "width": width, "height": height,
                     "environment": env_info, "camera": cam_info, "defines": args["defines"],
                     "parameters": params, "mitsuba_sampler": desc.sampler,
                     "mitsuba_filter": {"type": kind, "param": prm}})

    # -- render ----------------------------------------------------------------------------------
    out_dir = os.path.dirname(out_path)
    os.makedirs(out_dir, exist_ok=True)
    # render next to the output, then rename: a reader never sees a half-written EXR (the name
    # follows the output's, so renders into one folder can run side by side)
    stem = os.path.basename(out_path)
    stem = stem[:-4] if stem.lower().endswith(".exr") else stem
    tmp = os.path.join(out_dir, stem + ".tmp.exr")
    if os.path.exists(tmp):
        os.remove(tmp)
    sc.render.filepath = tmp
    log("rendering %dx%d, %d spp, max_depth %d (Cycles max_bounces %d), %d thread(s)"
        % (width, height, spp, max_depth, bounces, args["threads"]))
    t0 = time.time()
    try:
        bpy.ops.render.render(write_still=True)
        render_s = time.time() - t0
        if not os.path.isfile(tmp):
            raise RuntimeError("Blender did not write %s" % tmp)
        os.replace(tmp, out_path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    info = {
        "scene": scene_path, "output": out_path, "blender_version": bpy.app.version_string,
        "render_time_s": round(render_s, 3), "total_time_s": round(time.time() - t_start, 3),
        "approximations": APPROXIMATIONS, "notes": NOTES, "settings": settings,
        "command_line": argv, "triangles": ntri,
    }
    jtmp = out_path + ".json.tmp"
    with open(jtmp, "w") as f:
        json.dump(info, f, indent=2, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))
        f.write("\n")
    os.replace(jtmp, out_path + ".json")
    log("wrote %s (+ .json); render time %.2f s, total %.2f s, %d approximation(s)"
        % (out_path, render_s, time.time() - t_start, len(APPROXIMATIONS)))


def _uses_texture(b):
    return any(isinstance(v, Texture) for v in b.params.values()) or any(_uses_texture(x) for x in b.nested)


if __name__ == "__main__":
    try:
        main()
    except SceneError as e:
        print("ERROR: %s" % e, file=sys.stderr, flush=True)
        hard_exit(2)
    except SystemExit as e:
        hard_exit(e.code if isinstance(e.code, int) else 2)
    except Exception:
        traceback.print_exc()
        hard_exit(3)
    hard_exit(0)
