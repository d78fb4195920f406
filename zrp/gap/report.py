"""Write a :class:`~zrp.gap.Diagnosis` to a directory: diagnosis.json, report.md, PNG plots and
the withheld residuals as CSV.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from zrp.errors import OutputExistsError
from zrp.gap.pipeline import Diagnosis

__all__ = ["OUTPUT_FILES", "implicated_joint", "jsonable", "write_outputs"]

OUTPUT_FILES = ("diagnosis.json", "report.md", "residuals.csv", "residuals_before_after.png",
                "residual_vs_joint.png", "shrink.png")


def jsonable(obj: Any) -> Any:
    """``obj`` with NumPy values as Python ones and non-finite floats as None (strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def implicated_joint(diag: Diagnosis) -> int:
    """The joint to plot the residual against: among the joints of the first effect found
    (all joints when none was found), the one whose geometric parameters carry the largest
    share of the nominal residual (the "where" projection)."""
    n = diag.context.n
    cands = set(range(1, n + 1))
    for st in diag.steps:
        if st.joints and st.effect != "link_length":
            cands = {j for j in st.joints if j <= n}
            break
    proj = [p for p in diag.where.get("projection") or [] if p["joint"] in cands]
    if proj:
        return int(max(proj, key=lambda p: p["share"])["joint"])
    return min(cands) if cands else 1


def _rows(diag: Diagnosis) -> np.ndarray:
    return np.flatnonzero(np.isin(diag.context.meas.pose_index, diag.withheld_poses))


def _plots(diag: Diagnosis, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    unit = diag.length_unit
    eb = np.linalg.norm(diag.withheld_residual_before.reshape(-1, 3), axis=1)
    ea = np.linalg.norm(diag.withheld_residual_after.reshape(-1, 3), axis=1)
    rows = _rows(diag)
    floor = diag.noise_floor.rms

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    bins = np.linspace(0, max(eb.max(), ea.max()) * 1.02, 40)
    ax[0].hist(eb, bins=bins, alpha=0.6, label=f"after registration (RMS {diag.nominal.rms:.3g})")
    ax[0].hist(ea, bins=bins, alpha=0.6, label=f"after correction (RMS {diag.final.rms:.3g})")
    if floor is not None:
        ax[0].axvline(floor, color="k", ls="--", lw=1, label=f"noise floor RMS {floor:.3g}")
    ax[0].set_xlabel(f"withheld |error| ({unit})")
    ax[0].set_ylabel("points")
    ax[0].legend(fontsize=8)
    ax[1].plot(rows, eb, ".", ms=3, label="after registration")
    ax[1].plot(rows, ea, ".", ms=3, label="after correction")
    ax[1].set_xlabel("row (measurement order)")
    ax[1].set_ylabel(f"withheld |error| ({unit})")
    ax[1].legend(fontsize=8)
    fig.suptitle("Withheld residuals before and after the diagnosed corrections")
    fig.tight_layout()
    fig.savefig(out / "residuals_before_after.png", dpi=110)
    plt.close(fig)

    k = implicated_joint(diag)
    meas = diag.context.meas
    qk = meas.q[rows, k - 1]
    deg = not diag.context.model.prismatic[k - 1]
    x = np.degrees(qk) if deg else qk
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(x, eb, ".", ms=3, label="after registration")
    ax.plot(x, ea, ".", ms=3, label="after correction")
    ax.set_xlabel(f"q{k} ({'deg' if deg else unit})")
    ax.set_ylabel(f"withheld |error| ({unit})")
    ax.set_title(f"Residual against the implicated joint {k}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "residual_vs_joint.png", dpi=110)
    plt.close(fig)

    labels = ["registration"] + [f"+ {s.effect}" for s in diag.steps]
    rms = [diag.nominal.rms] + [s.withheld.rms for s in diag.steps]
    p95 = [diag.nominal.p95] + [s.withheld.p95 for s in diag.steps]
    fig, ax = plt.subplots(figsize=(max(6, 1.6 * len(labels)), 4))
    xs = np.arange(len(labels))
    ax.bar(xs - 0.2, rms, 0.4, label="RMS")
    ax.bar(xs + 0.2, p95, 0.4, label="p95")
    if floor is not None:
        ax.axhline(floor, color="k", ls="--", lw=1, label="noise floor RMS")
    ax.set_xticks(xs, labels, rotation=20, ha="right")
    ax.set_ylabel(f"withheld error ({unit})")
    ax.set_title("Shrink of the withheld error per step")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "shrink.png", dpi=110)
    plt.close(fig)


def _val(v: float, unit: str) -> str:
    if unit == "rad":
        return f"{v * 1e3:.4g} mrad ({math.degrees(v):.4g} deg)"
    return f"{v:.4g} {unit}"


def _ci(p: Any, unit: str) -> str:
    lo, hi = p.ci95
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "undetermined"
    if unit == "rad":
        return f"[{lo * 1e3:.4g}, {hi * 1e3:.4g}] mrad"
    return f"[{lo:.4g}, {hi:.4g}] {unit}"


def _candidate_table(cands: list[dict[str, Any]], u: str) -> list[str]:
    out = [f"| effect | joints | params | CV RMS ({u}) | dBIC | p | added? | note |",
           "|---|---|---|---|---|---|---|---|"]
    for c in cands:
        cv = "" if c["cv_rms"] is None else f"{c['cv_rms']:.4g}"
        db = "" if c["bic_delta"] is None else f"{c['bic_delta']:.1f}"
        out.append(f"| {c['effect']} | {', '.join(map(str, c['joints'])) or '-'} | "
                   f"{c['n_params']} | {cv} | {db} | {c['p_value']:.2g} | "
                   f"{'yes' if c['significant'] else 'no'} | {c['note']} |")
    out.append("")
    return out


def _markdown(diag: Diagnosis) -> str:
    u = diag.length_unit
    d = diag.to_dict()
    s = diag.settings
    nf = diag.noise_floor
    L: list[str] = []
    L.append(f"# Sim-to-real gap diagnosis: {diag.model_name}\n")
    L.append(f"Data: {diag.context.meas.source}: {s['n_poses']} poses, {s['n_points']} measured "
             f"points ({', '.join(s['point_labels'])}), frame `{s['frame']}`. Fitting set "
             f"{len(diag.fitting_poses)} poses, withheld set {len(diag.withheld_poses)} poses "
             f"(never used for fitting or selection), {s['folds']} cross-validation folds.\n")
    L.append("## Verdict\n")
    L.append(diag.verdict + "\n")
    L.append("## How far the gap shrinks (withheld poses)\n")
    L.append(f"| step | effect | joints | RMS ({u}) | p95 ({u}) | max ({u}) | CV RMS ({u}) "
             "| F-test p | dBIC |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    L.append(f"| 0 | registration (base_frame, tool_offset) | - | {diag.nominal.rms:.4g} | "
             f"{diag.nominal.p95:.4g} | {diag.nominal.max:.4g} | | | |")
    for i, st in enumerate(diag.steps, 1):
        L.append(f"| {i} | {st.effect} | {', '.join(map(str, st.joints)) or '-'} | "
                 f"{st.withheld.rms:.4g} | {st.withheld.p95:.4g} | {st.withheld.max:.4g} | "
                 f"{st.cv_rms:.4g} | {st.p_value:.2g} | {st.bic_delta:.1f} |")
    if nf.rms is not None:
        L.append(f"| | noise floor ({nf.method}) | | {nf.rms:.4g} | {nf.p95:.4g} | | | | |")
    L.append("")
    L.append(f"Final withheld RMS / nominal: {diag.shrink:.3f}. ")
    if nf.sigma is not None:
        L.append(f"Noise floor: sigma = {nf.sigma:.4g} {u} per coordinate from {nf.method} "
                 f"({nf.n_samples} samples); RMS of pure noise sqrt(3) sigma = {nf.rms:.4g} {u}."
                 + (" Distances between rigidly linked points measure the instrument's noise "
                    "only; the robot's repeatability adds to it, so the attainable floor is "
                    "somewhat higher." if nf.method == "rigid_links" else ""))
    L.append("\n![shrink](shrink.png)\n")
    L.append("![residuals](residuals_before_after.png)\n")
    L.append("![residual vs joint](residual_vs_joint.png)\n")
    L.append("## Identified parameters (final model, 95 % intervals)\n")
    L.append("Estimated jointly in the final model (the per-step values in diagnosis.json were "
             "each estimated before the later effects were added).\n")
    by_eff: dict[str, list[Any]] = {}
    for p in diag.final_parameters:
        by_eff.setdefault(p.effect, []).append(p)
    for eff, params in by_eff.items():
        L.append(f"### {eff} (joints {', '.join(map(str, diag.final_joints.get(eff, ()))) or '-'})"
                 "\n")
        L.append("| parameter | value | 95 % interval |")
        L.append("|---|---|---|")
        for p in params:
            L.append(f"| {p.name} | {_val(p.value, p.unit)} | {_ci(p, p.unit)} |")
        L.append("")
    for i, st in enumerate(diag.steps, 1):
        if not math.isnan(st.geometric_overlap):
            L.append(f"Step {i} ({st.effect}): geometric overlap "
                     f"{100 * st.geometric_overlap:.0f} %: that share of the step's correction "
                     "could also be produced by joint offsets, encoder scales, link and axis "
                     "errors over these poses"
                     + (" (so it is only weakly distinguishable from geometry; e.g. a first "
                        "harmonic overlaps an offset and a scale when a joint turns less than a "
                        "full turn)." if st.geometric_overlap > 0.5 else "."))
            L.append("")
    if diag.where.get("backward_pruned"):
        L.append("Dropped in the backward pass (no longer significant in the final model): "
                 + ", ".join(diag.where["backward_pruned"]) + ".\n")
    L.append("Registration:\n")
    L.append("| parameter | value | 95 % interval |")
    L.append("|---|---|---|")
    for p in diag.registration:
        L.append(f"| {p.name} | {_val(p.value, p.unit)} | {_ci(p, p.unit)} |")
    L.append("")
    L.append("## Which effect: ranking of the candidates\n")
    L.append("Ranked by cross-validated RMS within the fitting set; an effect is added when "
             "its F test is significant (p < alpha), its BIC falls and its CV RMS improves by at "
             "least 1 %.\n")
    if diag.steps:
        L.append("At step 1:\n")
        L.extend(_candidate_table([c.to_dict() for c in diag.steps[0].candidates], u))
    last = diag.where.get("last_candidates")
    if last:
        L.append(f"After step {len(diag.steps)} (none added):\n" if diag.steps
                 else "On top of the registration (none added):\n")
        L.extend(_candidate_table(last, u))
    L.append("## Parameters the data cannot tell apart\n")
    if diag.aliased:
        L.append("Reported, never absorbed silently: a dropped parameter is not estimated; "
                 "its effect is carried by its partners.\n")
        for a in diag.aliased:
            L.append(f"- {a.name} ({a.effect}) vs {', '.join(a.partners) or 'registration'}: "
                     f"{'not identifiable (dropped)' if a.dropped else 'weakly identifiable'}"
                     f" (independent share {a.fraction:.2g})")
        L.append("")
    surv = diag.where.get("identifiability", {})
    rows = [(eff, v) for eff, v in surv.items() if v["not_identifiable"]]
    if rows:
        L.append("Not identifiable on top of the registration, per effect (robot structure or "
                 "these poses; 'limited by data' means richer poses would identify it):\n")
        for eff, v in rows:
            items = ", ".join(f"{a['name']} ~ {'/'.join(a['partners']) or 'no effect'}"
                              for a in v["not_identifiable"])
            L.append(f"- {eff}: {items}")
            if v["limited_by_data"]:
                L.append(f"  - limited by data: {', '.join(v['limited_by_data'])}")
        L.append("")
    w = d["where"]
    L.append("## Where the gap lies (fitting poses, after registration)\n")
    L.append("RMS per point: " + ", ".join(f"{k} {v:.4g} {u}" for k, v in
                                            w["per_point"].items()) + ".\n")
    L.append("Share of the residual explained by a smooth function of each joint angle (R^2): "
             + ", ".join(f"q{j['joint']} {j['r2']:.2f}" for j in w["joints"]) + ".\n")
    extra = [f"measurement order {w['order']['r2']:.2f}"]
    if "time" in w:
        extra.append(f"time {w['time']['r2']:.2f}")
    if "temperature" in w:
        extra.append(f"temperature {w['temperature']['r2']:.2f}")
    L.append("R^2 against " + ", ".join(extra) + ".\n")
    L.append(f"Projection on the geometric parameters of each joint (share of the residual, "
             f"all together {w['geometric_share']:.2f}): "
             + ", ".join(f"joint {p['joint']} {p['share']:.2f}" for p in w["projection"])
             + ".\n")
    L.append("Singular directions of the identification Jacobian carrying most residual:\n")
    for c in w["components"]:
        L.append(f"- share {c['share']:.3f}, singular value {c['singular_value']:.3g}: "
                 + ", ".join(f"{p['name']} ({p['loading']:+.2f})" for p in c["parameters"]))
    L.append("\nWorkspace regions (horizontal radius x height):\n")
    for r in w["regions"]:
        L.append(f"- radius {r['radius'][0]:.0f}-{r['radius'][1]:.0f} {u}, {r['height']}: RMS "
                 f"{r['rms']:.4g} {u} ({r['n_points']} points)")
    wf = w.get("after_final_model")
    if wf:
        L.append("\n## What remains after the final model (fitting poses)\n")
        L.append("Share explained by a smooth function of each joint angle (R^2): "
                 + ", ".join(f"q{j['joint']} {j['r2']:.2f}" for j in wf["joints"])
                 + f"; measurement order {wf['order']['r2']:.2f}.\n")
        if "common_share" in wf:
            L.append(f"Common to all points of a pose (a shift of the whole tool): "
                     f"{100 * wf['common_share']:.0f} % of the remaining energy.\n")
        L.append("Workspace regions:\n")
        for r in wf["regions"]:
            L.append(f"- radius {r['radius'][0]:.0f}-{r['radius'][1]:.0f} {u}, {r['height']}: "
                     f"RMS {r['rms']:.4g} {u} ({r['n_points']} points)")
        L.append(f"\nGeometric parameters could still explain "
                 f"{100 * wf['geometric_share']:.0f} % of it.")
    if diag.warnings:
        L.append("\n## Warnings\n")
        L.extend(f"- {m}" for m in diag.warnings)
    L.append("\n## Method\n")
    L.append("See docs/diagnosis.md. Registration (base_frame, tool_offset) first; each "
             "candidate effect is a parametrised model correction fitted by least squares with "
             "analytic Jacobians; joints whose parameters fail a Wald test are pruned; "
             "candidates are ranked by cross-validated RMS and added greedily while an F test, "
             "BIC and the CV RMS agree that they help. Intervals are 95 % normal-theory "
             "intervals from the fit's covariance (they assume the model is right; with an "
             "unexplained gap they are optimistic).")
    return "\n".join(L) + "\n"


def write_outputs(diag: Diagnosis, out_dir: str | Path, *, force: bool = False,
                  plots: bool = True) -> list[Path]:
    """Write diagnosis.json, report.md, residuals.csv and (with ``plots``) the PNGs.

    Raises:
        OutputExistsError: when one of these files exists and ``force`` is False.
    """
    out = Path(out_dir)
    existing = [out / f for f in OUTPUT_FILES if (out / f).exists()]
    if existing and not force:
        raise OutputExistsError(f"{out}: {', '.join(p.name for p in existing)} already "
                                "exist(s); pass --force to overwrite")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    p = out / "diagnosis.json"
    p.write_text(json.dumps(jsonable(diag.to_dict()), indent=2) + "\n")
    written.append(p)
    meas = diag.context.meas
    rows = _rows(diag)
    rb = diag.withheld_residual_before.reshape(-1, 3)
    ra = diag.withheld_residual_after.reshape(-1, 3)
    p = out / "residuals.csv"
    with open(p, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["line", "pose", "point", "before_x", "before_y", "before_z", "before_norm",
                    "after_x", "after_y", "after_z", "after_norm"])
        for i, r in enumerate(rows):
            w.writerow([int(meas.lines[r]), meas.pose[r], meas.point[r],
                        *(f"{v:.6g}" for v in rb[i]), f"{np.linalg.norm(rb[i]):.6g}",
                        *(f"{v:.6g}" for v in ra[i]), f"{np.linalg.norm(ra[i]):.6g}"])
    written.append(p)
    if plots:
        _plots(diag, out)
        written += [out / f for f in OUTPUT_FILES[3:]]
    p = out / "report.md"
    p.write_text(_markdown(diag))
    written.append(p)
    return written
