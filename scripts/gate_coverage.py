#!/usr/bin/python3
"""What the occlusion term Ĩc sees, per shape, in a fit (issue 16 item 4; docs/results.md).

Ĩc adds β·L̃c(shape)·G at a camera path's first non-delta vertex, Ĩa adds β·L̃a(shape) there
(docs/transport.md (6), (7)). Both are linear in their vectors, so two renders of the fitted model
with the same paths measure the gate without touching the integrator:

    A: L̃a(shape i) = e_i (the i-th unit channel), every other vector 0  → channel i of A, summed
       over pixels, is proportional to Σ β over the samples whose first non-delta vertex lies
       on shape i
    B: L̃c(shape i) = e_i, every other vector 0                           → the same with Σ β·G

    coverage_i = Σ B_i / Σ A_i     (the β-weighted fraction of the shape's samples with G = 1)
    share_i    = Σ A_i / Σ_j Σ A_j (how much of the view the shape is)

β is per channel: a shape seen through a mirror is weighted by that mirror's channel i, which
moves the average but keeps it in [0, 1]. Shapes go through in groups of 16 (one channel each);
the same seed gives the same paths in every group.

At coverage 1 (the "shadowed" gate: G ≡ 1, the NEE sample never lit) L̃c gets the same gradient
as L̃a, so only their sum is determined; at coverage 0 it gets none. The report prints the
fitted |L̃a|, |L̃c| and their cosine beside the coverage.

    PYTHONPATH=build/python /usr/bin/python3 scripts/gate_coverage.py results-paper/cbox-specular/fit_eac

Needs the Python module (Debian's /usr/bin/python3; docs/python.md).
"""
import argparse
import json
import os
import sys

import numpy as np

import latentpt

CHANNELS = 16  # of the latent
GROUP = CHANNELS  # shapes per pair of renders, one channel each


def zeroed(model):
    """Every emission, flat-response, occlusion and background vector set to 0."""
    for s in model.slices():
        if s["kind"] in ("Le", "La", "Lc", "background"):
            model.set_value(s["name"], np.zeros(s["channels"], np.float32))


def shapes_with(model, kind):
    return [s["name"].rsplit(".", 1)[0] for s in model.slices() if s["kind"] == kind]


def render_unit_vectors(model, kind, shapes, **render):
    """Per-channel pixel sums of the linear latent with `kind` of shapes[i] set to e_i, all other
    vectors 0."""
    zeroed(model)
    for i, shape in enumerate(shapes):
        e = np.zeros(CHANNELS, np.float32)
        e[i] = 1.0
        model.set_value(f"{shape}.{kind}", e)
    img = model.render_linear(**render)
    return img.reshape(-1, img.shape[-1]).sum(axis=0, dtype=np.float64)[:len(shapes)]


def gate_coverage(model, width=0, height=0, spp=16, seed=1):
    """{shape: (share, coverage)}. Every L̃ vector of `model` is 0 afterwards."""
    shapes = shapes_with(model, "Lc")
    render = dict(width=width, height=height, spp=spp, seed=seed)
    flat, occluded = [], []
    for g in range(0, len(shapes), GROUP):
        group = shapes[g:g + GROUP]
        flat += list(render_unit_vectors(model, "La", group, **render))
        occluded += list(render_unit_vectors(model, "Lc", group, **render))
    zeroed(model)
    total = sum(flat)
    if total <= 0:
        raise ValueError("no camera path reaches a non-delta surface")
    return {shape: (flat[i] / total, occluded[i] / flat[i] if flat[i] > 0 else float("nan"))
            for i, shape in enumerate(shapes)}


def fit_terms(fit):
    """The terms a fit folder was fitted with (fit.json), or None when it does not say."""
    try:
        with open(os.path.join(fit, "fit.json")) as f:
            return json.load(f).get("terms")
    except (OSError, ValueError):
        return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("fit", help="a fit folder fitted with --terms eac")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--width", type=int, default=0, help="latent width (default: the fit's)")
    ap.add_argument("--height", type=int, default=0)
    a = ap.parse_args()
    terms = fit_terms(a.fit)
    if terms is None or "a" not in terms or "c" not in terms:
        sys.exit(f"gate_coverage: {a.fit}/fit.json: terms '{terms}' lack Ĩa and Ĩc (fit with --terms eac)")
    model = latentpt.LatentScene.from_fit(a.fit)
    fitted = {s["name"]: model.value(s["name"]) for s in model.slices()}
    try:
        cover = gate_coverage(model, a.width, a.height, a.spp, a.seed)
    except ValueError as e:
        sys.exit(f"gate_coverage: {a.fit}: {e}")
    print(f"{a.fit}: {model.width}x{model.height} latents, {a.spp} spp, seed {a.seed}")
    print(f"{'shape':24s} {'share':>7s} {'coverage':>9s} {'|La|':>6s} {'|Lc|':>6s} {'cos(La,Lc)':>10s}")
    for shape, (share, cov) in cover.items():
        la, lc = np.asarray(fitted[f"{shape}.La"]), np.asarray(fitted[f"{shape}.Lc"])
        cos = float(la @ lc / max(1e-12, np.linalg.norm(la) * np.linalg.norm(lc)))
        print(f"{shape:24s} {share:7.3f} {cov:9.3f} {np.linalg.norm(la):6.2f} {np.linalg.norm(lc):6.2f} {cos:10.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
