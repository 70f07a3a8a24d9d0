"""The paper's Table 1 (Radovanovic et al., CGF 2026) beside ours: its values, the issue-16 targets
checked per cell, the table as markdown (summary.md, reference_noise.md) and HTML (report.html),
and Table 1 built from scripts/reference_noise.py's scores against the first, the independent or
both references of every scored frame. Standard library only; experiment_lib re-exports it."""
import html


# The paper's Table 1 (mean LPIPS / MSE×100 of the decoded RGB over each 60-frame sequence;
# 1024² images, SD3.5's VAE, LPIPS with AlexNet), keyed like our tables.
PAPER_NAMES = {"cbox-specular": "Cornell Box", "veach-bidir": "Lamp", "dining-room": "Living Room"}
PAPER_TABLE1 = {
    "cbox-specular": {"camera": [(0.502, 2.264), (0.228, 0.335), (0.213, 0.222), (0.075, 0.069)],
                      "object": [(0.526, 2.355), (0.213, 0.338), (0.202, 0.261), (0.032, 0.061)],
                      "light": [(0.519, 2.361), (0.209, 0.330), (0.191, 0.220), (0.013, 0.024)]},
    "veach-bidir": {"camera": [(0.394, 3.091), (0.206, 0.844), (0.178, 0.564), (0.068, 0.297)],
                    "object": [(0.439, 3.274), (0.236, 0.791), (0.202, 0.608), (0.020, 0.048)],
                    "light": [(0.504, 5.702), (0.292, 3.000), (0.253, 2.385), (0.086, 1.867)]},
    "dining-room": {"camera": [(0.643, 5.502), (0.281, 0.599), (0.250, 0.480), (0.072, 0.115)],
                    "object": [(0.648, 5.584), (0.280, 0.573), (0.246, 0.451), (0.008, 0.013)],
                    "light": [(0.659, 6.031), (0.299, 1.053), (0.266, 0.894), (0.064, 0.392)]}}
TABLE1_COLUMNS = [("e", "Ĩe"), ("ea", "+Ĩa"), ("eac", "+Ĩc"), ("eac+refiner", "+refiner")]
TABLE1_NOTE = ("Mean over the evaluated frames; the paper's values (in brackets) are SD3.5's VAE and AlexNet LPIPS "
               "over all 60 frames at 1024²; ours are TAESD3 and SqueezeNet LPIPS. VAE round trip: the training "
               "view's reference encoded and decoded by TAESD3, the floor no latent can beat (one value per scene, "
               "repeated on its rows).")
TABLE1_TARGETS = ("each column below the one before it in both metrics; the +refiner column at most the paper's "
                  "value where the round trip is below it, else at most 1.5× the round trip. The issue sets them "
                  "for cbox-specular at 128² latents; they are checked here on every scene.")
ISSUE_SCENE = "cbox-specular"  # the scene issue 16's targets are stated for


def misses_line(misses, lead):
    """`lead` and how many targets missed, with the issue's own scene's share when others are in the table."""
    if not misses:
        return lead + " All met."
    own = sum(1 for x in misses if x.startswith(ISSUE_SCENE + "/"))
    scope = f" ({own} on {ISSUE_SCENE}, the scene the issue sets them for)" if 0 < own < len(misses) else ""
    return f"{lead} {len(misses)} missed{scope}:"


def table1_rows(c, summary):
    """The paper's Table 1 checked against the issue-16 targets, one row per scene and edit: each
    column better than the one before it in both metrics; refined ≤ the paper's value where the
    round trip (training view) is below it, else ≤ 1.5× the round trip. A column an edit's table
    lacks (a study that scored only some fits) is None and left out of the ordering: it is
    compared with the nearest column before it that is there. Returns (rows, misses): a row is
    {label, kind, ours: [(LPIPS, MSE×100) or None per column], paper, floor, missed: {(column,
    metric index)}}, misses the target misses as sentences."""
    rows, misses = [], []
    for scene, s in summary.items():
        rt = s["training_view"].get("vae_roundtrip", {})
        floor = (rt.get("rgb_lpips", float("nan")), rt.get("rgb_mse_x100", float("nan")))
        for kind in ("camera", "object", "light"):
            table, paper = s["edits"][kind], PAPER_TABLE1[scene][kind]
            ours = [(table[k]["rgb_lpips"], table[k]["rgb_mse_x100"]) if k in table else None for k, _ in TABLE1_COLUMNS]
            res = c.get("scene_res", {}).get(scene, c["image_res"])  # experiment_lib.image_res_of
            row = {"label": f"{PAPER_NAMES[scene]} {res}²", "kind": kind, "ours": ours, "paper": paper,
                   "floor": floor, "missed": set()}
            present = [j for j, o in enumerate(ours) if o]
            for m, metric in enumerate(("LPIPS", "MSE×100")):
                for i, j in zip(present, present[1:]):
                    if not ours[j][m] < ours[i][m]:
                        row["missed"].add((j, m))
                        misses.append(f"{scene}/{kind} {metric}: {TABLE1_COLUMNS[j][1]} {ours[j][m]:.3f} not below "
                                      f"{TABLE1_COLUMNS[i][1]} {ours[i][m]:.3f}")
                if not ours[-1]:
                    continue
                bound = paper[-1][m] if floor[m] < paper[-1][m] else 1.5 * floor[m]
                if not ours[-1][m] <= bound:
                    row["missed"].add((len(ours) - 1, m))
                    # a fourth digit where three would print the value and its bound alike
                    d = 4 if f"{ours[-1][m]:.3f}" == f"{bound:.3f}" else 3
                    misses.append(f"{scene}/{kind} {metric}: refined {ours[-1][m]:.{d}f} above "
                                  f"{'the paper' if floor[m] < paper[-1][m] else '1.5× the round trip'} {bound:.{d}f}")
            rows.append(row)
    return rows, misses


def table1(c, summary):
    """Table 1 as markdown, ours beside the paper's value in every cell and each scene's VAE round
    trip as the floor (table1_rows). Returns (markdown lines, misses)."""
    rows, misses = table1_rows(c, summary)
    md = ["| scene | edit | " + " | ".join(lab for _, lab in TABLE1_COLUMNS) + " | VAE round trip |",
          "|---|---|" + "---|" * (len(TABLE1_COLUMNS) + 1)]
    for r in rows:
        cells = [(f"{o[0]:.3f} / {o[1]:.3f}" if o else "–") + f" ({p[0]:.3f} / {p[1]:.3f})" for o, p in zip(r["ours"], r["paper"])]
        md.append(f"| {r['label']} | {r['kind']} | " + " | ".join(cells) + f" | {r['floor'][0]:.3f} / {r['floor'][1]:.3f} |")
    return md, misses


def table1_html(c, summary, title):
    """Table 1 for report.html: a value that misses its target in red, the paper's in grey."""
    rows, misses = table1_rows(c, summary)

    def value(r, j, m):
        v = f"{r['ours'][j][m]:.3f}" if r["ours"][j] else "–"
        return f'<span class="miss">{v}</span>' if (j, m) in r["missed"] else v

    h = [f"<h2>{html.escape(title)}</h2>", "<p>LPIPS / MSE×100, ours <span class='paper'>(paper's)</span>; "
         f"<span class='miss'>red</span>: a target missed. {html.escape(TABLE1_NOTE)}</p>",
         f"<p>{html.escape(misses_line(misses, 'Targets (issue 16): ' + TABLE1_TARGETS).rstrip(':'))}</p>",
         "<table class='t1'><tr><th>scene</th><th>edit</th>" + "".join(f"<th>{html.escape(lab)}</th>" for _, lab in TABLE1_COLUMNS) +
         "<th>VAE round trip</th></tr>"]
    for r in rows:
        cells = "".join(f"<td>{value(r, j, 0)} / {value(r, j, 1)}<br><span class='paper'>({p[0]:.3f} / {p[1]:.3f})</span></td>"
                        for j, p in enumerate(r["paper"]))
        h.append(f"<tr><td>{html.escape(r['label'])}</td><td>{r['kind']}</td>{cells}"
                 f"<td>{r['floor'][0]:.3f} / {r['floor'][1]:.3f}</td></tr>")
    return h + ["</table>"] + (["<ul>"] + [f"<li>{html.escape(x)}</li>" for x in misses] + ["</ul>"] if misses else [])


# Table 1 from reference_noise.py's rows, by the reference the cells are scored against:
# (LPIPS key, MSE×100 of a row's column, the floor (LPIPS, MSE×100) from the round trip's scores).
#   r1:   the experiment's reference (its protocol). Same seed as the training target, so fixed-camera
#         frames share its noise, which a refiner trained on that target partly reproduces.
#   r2:   the independent reference (--ref-seed 1), MSE×100 less its variance σ²: an unbiased
#         estimate against the converged image; LPIPS at the same noise level as r₁.
#   mean: r̄ = ½ (r₁ + r₂), MSE×100 noise-corrected; LPIPS at half the noise, which a decoded latent
#         carrying a 512-spp reference's texture matches less well (docs/results.md).
NOISE_MEASURES = {
    "r1": ("lpips_r1", lambda row, col: col["mse_r1"], lambda fl: (fl["lpips_r1"], fl["mse_r1"])),
    "r2": ("lpips_r2", lambda row, col: col["mse_r2"] - row["sigma2_x100"], lambda fl: (fl["lpips_r2"], fl["mse_r2_corrected"])),
    "mean": ("lpips_mean_ref", lambda row, col: col["mse_corrected"],
             lambda fl: (fl["lpips_mean_ref_roundtrip"], fl["mse_r2_corrected"])),
}


def noise_table1_entry(result, measure):
    """table1()'s entry of one scene from reference_noise.py's result, its four columns and floor
    scored against the reference NOISE_MEASURES[measure] names (frame means)."""
    lpips_key, mse_of, floor_of = NOISE_MEASURES[measure]
    floor = floor_of(result["floor"])

    def column(rows, k):
        return {"rgb_lpips": sum(r[k][lpips_key] for r in rows) / len(rows),
                "rgb_mse_x100": sum(mse_of(r, r[k]) for r in rows) / len(rows)}

    edits = {seq: {k: column(rows, k) for k in rows[0] if k not in ("frame", "sigma2_x100")}
             for seq, rows in result["sequences"].items()}
    return {"training_view": {"vae_roundtrip": {"rgb_lpips": floor[0], "rgb_mse_x100": floor[1]}}, "edits": edits}


def independent_table1_summary(noise):
    """table1()'s input against the independent references (NOISE_MEASURES "r2"), or None where a
    scene is not the paper's or lacks an edit sequence."""
    entries = {scene: noise_table1_entry(n, "r2") for scene, n in noise.items()}
    ok = all(scene in PAPER_TABLE1 and set(e["edits"]) == set(PAPER_TABLE1[scene]) for scene, e in entries.items())
    return entries if ok else None
