"""report.md: the diagnosis for a reader (verdict, shrink table, parameters, ranking, aliasing,
where the gap lies, warnings, method).

Every string that comes from the user's files (model name, data file, point labels, names,
warnings that quote them) passes through :func:`zrp.escape.md_text`: one line, Markdown and
HTML punctuation escaped, so a label can add neither a section nor a table cell nor a tag."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from zrp.escape import md_text as _t
from zrp.gap.analysis.where import Region, WhereAnalysis
from zrp.gap.report.backlash import backlash_flank_text
from zrp.gap.report.fullpose import full_pose_markdown
from zrp.gap.report.headline import effect_joints, headline_text, summary_markdown
from zrp.gap.report.identification import identification_markdown
from zrp.gap.report.verdict import (
    baseline_text,
    final_effects_text,
    held_names,
    verdict_sections,
)
from zrp.gap.results import Candidate, Diagnosis, ParameterEstimate
from zrp.gap.search.determination import Determination

__all__ = ["decimals", "report_markdown", "value_ci"]


def decimals(half_width: float) -> int:
    """Decimals that show an interval of this half-width with two significant digits."""
    if not (half_width > 0 and math.isfinite(half_width)):
        return 4
    return max(0, 1 - math.floor(math.log10(half_width)))


def value_ci(v: float, lo: float, hi: float, unit: str) -> tuple[str, str]:
    """(value, [lo, hi]) at a precision that shows the interval (rad shown as mrad)."""
    k, u = (1e3, "mrad") if unit == "rad" else (1.0, unit)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{v * k:.4g} {u}", "undetermined"
    big = max(abs(v), abs(lo), abs(hi)) * k
    if unit != "rad" and 0 < big < 1e-2:  # tiny (compliance, kappa): a power of ten
        e = math.floor(math.log10(big))
        k, u = k * 10.0**-e, f"x 1e{e} {u}".rstrip()
    d = decimals(0.5 * (hi - lo) * k)
    return f"{v * k:.{d}f} {u}", f"[{lo * k:.{d}f}, {hi * k:.{d}f}] {u}"


def _joints(joints: Sequence[int]) -> str:
    return ", ".join(map(str, joints)) or "-"


def _status(p: ParameterEstimate, det: Mapping[str, Determination], bad: bool) -> str:
    """What the data say about one parameter, in a table cell."""
    d = det.get(p.name)
    if bad:
        return "NO: outside its physical domain"
    if d is None or d.determined:
        return "determined, plausible"
    if d.status == "held":
        return f"in a combination held at nominal: {_t(d.direction.split(' (')[0])}"
    return f"undetermined: {_t(d.direction)}"


def _parameter_table(params: Sequence[ParameterEstimate], *, flags: Sequence[str] = (),
                     det: Mapping[str, Determination] | None = None) -> list[str]:
    """One row per parameter: value, interval (none for a held one: the data did not move
    it) and what the data say (:mod:`zrp.gap.search.determination`)."""
    det = det or {}
    joint = any(p.ci95_effect is not None for p in params)
    out = (["| parameter | value | 95 % interval | 95 % for the whole effect | the data |",
            "|---|---|---|---|---|"] if joint else
           ["| parameter | value | 95 % interval | the data |", "|---|---|---|---|"])
    for p in params:
        v, ci = value_ci(p.value, *p.ci95, p.unit)
        held = p.name in det and det[p.name].status == "held"
        bad = any(f.startswith(p.name + " = ") for f in flags)
        both = "" if not joint else (
            f"{value_ci(p.value, *p.ci95_effect, p.unit)[1]} | " if p.ci95_effect else "| ")
        if held:
            ci, both = "not pinned (held)", ("not pinned (held) | " if joint else "")
        out.append(f"| {_t(p.name)} | {v} | {ci} | {both}{_status(p, det, bad)} |")
    return out


def _candidate_table(cands: Sequence[Candidate], u: str, added: str | None) -> list[str]:
    out = [f"| effect | joints | params | CV RMS ({u}) | dBIC | p | passes all tests | "
           "added at this step | note |", "|---|---|---|---|---|---|---|---|---|"]
    for c in cands:
        cv = "" if math.isnan(c.cv_rms) else f"{c.cv_rms:.4g}"
        db = "" if math.isnan(c.bic_delta) else f"{c.bic_delta:.1f}"
        out.append(f"| {c.effect} | {_joints(c.joints)} | {c.n_params} | {cv} | {db} | "
                   f"{c.p_value:.2g} | {'yes' if c.significant else 'no'} | "
                   f"{'yes' if c.effect == added else 'no'} | {c.note} |")
    out.append("")
    return out


def _regions(regions: Sequence[Region], u: str) -> list[str]:
    return [f"- radius {r.radius[0]:.0f}-{r.radius[1]:.0f} {u}, {r.height}: RMS {r.rms:.4g} "
            f"{u} ({r.n_points} points)" for r in regions]


def _header(diag: Diagnosis) -> list[str]:
    s = diag.settings
    return [f"# Sim-to-real gap diagnosis: {_t(diag.model_name)}\n",
            "## Verdict\n",
            headline_text(diag) + "\n",
            *summary_markdown(diag), "",
            *(f"### {title}\n\n{text}\n" for title, text in verdict_sections(diag)),
            "## Data\n",
            f"Data: {_t(diag.context.meas.source)}: {s['n_poses']} poses, {s['n_points']} "
            f"measured points ({', '.join(map(_t, s['point_labels']))}), frame "
            f"`{s['frame']}`. Fitting set "
            f"{len(diag.fitting_poses)} poses, withheld set {len(diag.withheld_poses)} poses "
            "(never used for fitting; only to choose between the search's model and the "
            f"geometric calibration), {s['folds']} cross-validation folds.\n"]


#: the figures report.md shows (file, alt text), when the plots are written beside it
FIGURES = (("shrink.png", "shrink"), ("residuals_before_after.png", "residuals"),
           ("residual_vs_joint.png", "residual vs joint"), ("residual_map.png", "workspace"),
           ("correlation.png", "correlation"))
_FINAL_ROW = {"search": "final model after pruning",  # per source (analysis/fallback.py)
              "geometric_baseline": "the geometric calibration (the search's model was worse "
              "on withheld poses)", "geometric_plus_non_geometric": "the geometric calibration "
              "+ the search's non-geometric effects (clearly better than both on withheld poses)"}


def _shrink(diag: Diagnosis, figures: bool = True) -> list[str]:
    u, nf, nom = diag.length_unit, diag.noise_floor, diag.nominal
    L = ["## How far the gap shrinks (withheld poses)\n",
         f"| step | effect | joints | RMS ({u}) | p95 ({u}) | max ({u}) | CV RMS ({u}) "
         "| F-test p | dBIC |",
         "|---|---|---|---|---|---|---|---|---|",
         f"| 0 | registration (base_frame, tool_offset) | - | {nom.rms:.4g} | {nom.p95:.4g} | "
         f"{nom.max:.4g} | | | |"]
    for i, st in enumerate(diag.steps, 1):
        w = st.withheld
        L.append(f"| {i} | {st.effect} | {_joints(st.joints)} | {w.rms:.4g} | {w.p95:.4g} | "
                 f"{w.max:.4g} | {st.cv_rms:.4g} | {st.p_value:.2g} | {st.bic_delta:.1f} |")
    fin = diag.final
    a = diag.assessment
    what = _FINAL_ROW["search" if a is None or a.choice is None else a.choice.source]
    L.append(f"| final | {what}: {final_effects_text(diag) or 'none'} | | "
             f"{fin.rms:.4g} | {fin.p95:.4g} | {fin.max:.4g} | | | |")
    if a is not None:
        b = a.baseline
        L.append(f"| baseline | complete geometric calibration, plain ({b.n_parameters} "
                 f"parameters; the reference) | all | {b.withheld.rms:.4g} | "
                 f"{b.withheld.p95:.4g} | {b.withheld.max:.4g} | {b.cv_rms:.4g} | | |")
        if b.held is not None:
            L.append(f"| baseline, held | the same held in the physical domains (left them: "
                     f"{held_names(b)}) | all | {b.held.rms:.4g} | {b.held.p95:.4g} | "
                     f"{b.held.max:.4g} | | | |")
        if b.combined is not None:
            L.append(f"| baseline + | geometric calibration + {', '.join(b.non_geometric)} | "
                     f"| {b.combined.rms:.4g} | {b.combined.p95:.4g} | {b.combined.max:.4g} "
                     "| | | |")
    if nf.rms is not None:
        L.append(f"| | noise floor ({nf.method}) | | {nf.rms:.4g} | {nf.p95:.4g} | | | | |")
    else:
        L.append("| | noise floor | | cannot be estimated (one point per pose, no repeats) "
                 "| | | | | |")
    L.append("")
    if a is not None:
        L.append(baseline_text(diag) + "\n")
    L.append(f"Steps 1..{len(diag.steps)} show each effect as it was added; the final row is the "
             "jointly refitted model after the backward pass, or the baseline row that beat it "
             "on the withheld poses (diagnosis.json's `final_model`; the one the verdict, the "
             "parameter tables and diagnosis.json's `final` describe). Final withheld RMS / "
             f"nominal: {diag.shrink:.3f}. ")
    if nf.sigma is not None:
        L.append(f"Noise floor: sigma = {nf.sigma:.4g} {u} per coordinate from {nf.method} "
                 f"({nf.n_samples} samples); RMS of pure noise sqrt(3) sigma = {nf.rms:.4g} {u}."
                 + (" Distances between rigidly linked points measure the instrument's noise "
                    "only; the robot's repeatability adds to it, so the attainable floor is "
                    "somewhat higher." if nf.method == "rigid_links" else ""))
    if figures:
        L.append("")
        L += [f"![{alt}]({name})\n" for name, alt in FIGURES]
    return L


def _parameters(diag: Diagnosis) -> list[str]:
    flags = diag.assessment.implausible if diag.assessment is not None else ()
    det = diag.determination
    L = ["## Identified parameters (final model, robust 95 % intervals)\n",
         "Estimated jointly in the final model (the per-step values in diagnosis.json were "
         "each estimated before the later effects were added). Intervals: the largest of the "
         "pose-clustered jackknife, the sandwich and the normal-theory standard error, so "
         "they hold when a gap remains; \"for the whole effect\": simultaneous intervals that "
         "hold for all parameters of the effect at once (Sidak). Backlash is the full play. "
         + ("" if diag.assessment is None or diag.assessment.compliance is None else
            "Compliance: " + diag.assessment.compliance["note"] + ".") + "\n"]
    by_eff: dict[str, list[ParameterEstimate]] = {}
    for p in diag.final_parameters:
        by_eff.setdefault(p.effect, []).append(p)
    for eff, params in by_eff.items():
        L.append(f"### {effect_joints(eff, diag.final_joints.get(eff, ()))}\n")
        L += _parameter_table(params, flags=flags, det=det)
        L.append("")
        if eff == "backlash" and backlash_flank_text(diag):
            L.append(backlash_flank_text(diag) + "\n")
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
    if diag.where.backward_pruned:
        L.append("Dropped in the backward pass (no longer significant in the final model): "
                 + ", ".join(diag.where.backward_pruned) + ".\n")
    L += _frame(diag)
    return L


def _frame(diag: Diagnosis) -> list[str]:
    a = diag.assessment
    if a is None:
        return ["Registration:\n", *_parameter_table(diag.registration,
                                                     det=diag.determination), ""]
    f, u = a.frame, diag.length_unit
    L = ["## Registration (final model, robust 95 % intervals)\n"]
    if f.frame == "base":
        L.append("Data given in the robot's base frame: no instrument transform fitted.\n")
    else:
        L.append("Instrument-from-base transform (a point x in the base frame is measured at "
                 "R x + t); R as Z-Y-X angles (R = Rz(yaw) Ry(pitch) Rx(roll)) and as a "
                 "rotation vector:\n")
        L += ["| quantity | value | 95 % interval |", "|---|---|---|"]
        for q in (*f.zyx, *f.rotvec, *f.translation):
            v, ci = value_ci(q.value, *q.ci95, q.unit)
            if q.unit == "rad":
                v += f" ({math.degrees(q.value):.4f} deg)"
            L.append(f"| {_t(q.name)} | {v} | {ci} |")
        L.append("")
    L += ["Tool points (flange frame at the zero reference):\n",
          f"| point | x ({u}) | y ({u}) | z ({u}) |", "|---|---|---|---|"]
    for lab, qs in f.tool_points.items():
        cells = []
        for q in qs:
            v, ci = value_ci(q.value, *q.ci95, "")
            cells.append(f"{v.strip()} {ci.strip()}")
        L.append(f"| {_t(lab)} | " + " | ".join(cells) + " |")
    L.append("")
    det = diag.determination
    loose = [det[p.name] for p in diag.registration if not det[p.name].determined]
    if loose:
        L.append("Not determined by these data (the controller files flag them):\n")
        L += [f"- {_t(d.name)}: {_t(d.describe())}" for d in loose]
        L.append("")
    return L


def _trust(diag: Diagnosis) -> list[str]:
    a = diag.assessment
    if a is None:
        return []
    L = ["## How far to trust the numbers\n"]
    if a.implausible:
        L.append("Physically implausible final values:\n")
        L += [f"- {_t(m)}" for m in a.implausible]
        L.append("")
    if a.unexcited:
        L.append(f"Joints the data do not excite (no scale, cyclic error or backlash placed on "
                 f"them): {', '.join(map(str, a.unexcited))}.\n")
    c = a.correlations
    L.append(f"Strongly correlated parameter pairs (|rho| >= {0.9}; their values trade "
             f"against each other, the sums are better determined than each): "
             f"{len(c.strong)} of {len(c.names) * (len(c.names) - 1) // 2}. The full matrix is "
             "in diagnosis.json (`correlation`) and report.html.\n")
    L += [f"- {_t(x)} ~ {_t(y)}: {rho:+.3f}" for x, y, rho in c.strong[:20]]
    if len(c.strong) > 20:
        L.append(f"- ... and {len(c.strong) - 20} more")
    L += ["", "What remains, weighed against the data's own evidence:\n",
          "| explanation | the data | evidence |", "|---|---|---|"]
    L += [f"| {e} | {st} | {v} |" for e, st, v in a.remainder.findings()]
    L.append("")
    return L


def _ranking(diag: Diagnosis) -> list[str]:
    u = diag.length_unit
    L = ["## Which effect: ranking of the candidates\n",
         "Ranked by cross-validated RMS within the fitting set; an effect is added when its F "
         "test is significant (p < alpha), its BIC falls and its CV RMS improves by at least "
         "1 %.\n"]
    if diag.steps:
        L.append("At step 1:\n")
        L += _candidate_table(diag.steps[0].candidates, u, diag.steps[0].effect)
    last = diag.where.last_candidates
    if last:
        L.append(f"After step {len(diag.steps)} (none added):\n" if diag.steps
                 else "On top of the registration (none added):\n")
        L += _candidate_table(last, u, None)
    return L


def _aliasing(diag: Diagnosis) -> list[str]:
    L = ["## Parameters the data cannot tell apart\n"]
    if diag.aliased:
        L.append("Reported, never absorbed silently: a dropped parameter is not estimated; "
                 "its effect is carried by its partners.\n")
        for a in diag.aliased:
            L.append(f"- {_t(a.name)} ({a.effect}) vs "
                     f"{', '.join(map(_t, a.partners)) or 'registration'}: "
                     f"{'not identifiable (dropped)' if a.dropped else 'weakly identifiable'}"
                     f" (independent share {a.fraction:.2g})")
        L.append("")
    rows = [(eff, v) for eff, v in diag.where.identifiability.items() if v.not_identifiable]
    if rows:
        L.append("Not identifiable on top of the registration, per effect (robot structure or "
                 "these poses; 'limited by data' means richer poses would identify it):\n")
        for eff, v in rows:
            items = ", ".join(f"{_t(a.name)} ~ {'/'.join(map(_t, a.partners)) or 'no effect'}"
                              for a in v.not_identifiable)
            L.append(f"- {eff}: {items}")
            if v.limited_by_data:
                L.append(f"  - limited by data: {', '.join(v.limited_by_data)}")
        L.append("")
    return L


def _where(w: WhereAnalysis, u: str) -> list[str]:
    extra = [f"measurement order {w.order_r2:.2f}"]
    if w.time_r2 is not None:
        extra.append(f"time {w.time_r2:.2f}")
    if w.temperature_r2 is not None:
        extra.append(f"temperature {w.temperature_r2:.2f}")
    L = ["## Where the gap lies (fitting poses, after registration)\n",
         "RMS per point: " + ", ".join(f"{_t(k)} {v:.4g} {u}" for k, v in w.per_point.items())
         + ".\n",
         "Share of the residual explained by a smooth function of each joint angle (R^2): "
         + ", ".join(f"q{j.joint} {j.r2:.2f}" for j in w.joints) + ".\n",
         "R^2 against " + ", ".join(extra) + ".\n",
         f"Projection on the geometric parameters of each joint (share of the residual, "
         f"all together {w.geometric_share:.2f}): "
         + ", ".join(f"joint {p.joint} {p.share:.2f}" for p in w.projection) + ".\n",
         "Singular directions of the identification Jacobian carrying most residual:\n"]
    for c in w.components:
        L.append(f"- share {c.share:.3f}, singular value {c.singular_value:.3g}: "
                 + ", ".join(f"{_t(n)} ({v:+.2f})" for n, v in c.parameters))
    L.append("\nWorkspace regions (horizontal radius x height):\n")
    return L + _regions(w.regions, u)


def _remains(wf: WhereAnalysis, u: str) -> list[str]:
    L = ["\n## What remains after the final model (fitting poses)\n",
         "Share explained by a smooth function of each joint angle (R^2): "
         + ", ".join(f"q{j.joint} {j.r2:.2f}" for j in wf.joints)
         + f"; measurement order {wf.order_r2:.2f}.\n"]
    if wf.common_share is not None:
        L.append(f"Common to all points of a pose (a shift of the whole tool): "
                 f"{100 * wf.common_share:.0f} % of the remaining energy.\n")
    L.append("Workspace regions:\n")
    L += _regions(wf.regions, u)
    L.append(f"\nGeometric parameters could still explain {100 * wf.geometric_share:.0f} % of "
             "it.")
    return L


METHOD = ("See zrp/gap/README.md. Registration (base_frame, tool_offset) first; each "
          "candidate effect is a parametrised model correction fitted by least squares with "
          "analytic Jacobians; joints whose parameters fail a Wald test are pruned; "
          "candidates are ranked by cross-validated RMS and added greedily while an F test, "
          "BIC and the CV RMS agree that they help; a backward pass drops what the final "
          "model no longer needs. Final intervals are robust 95 % intervals (pose-clustered "
          "jackknife covariance, never narrower than the sandwich or the normal-theory "
          "ones); per-step intervals in diagnosis.json are normal-theory. A complete "
          "geometric calibration (QR-reduced base set of joint offsets, body vectors and axis "
          "tilts) is always fitted beside the chosen effects, and it is the final model when "
          "the effects found do not beat it on the withheld poses.")


def report_markdown(diag: Diagnosis, *, figures: bool = True) -> str:
    """The text of report.md (linking the plots beside it when ``figures``)."""
    u = diag.length_unit
    L = (_header(diag) + _shrink(diag, figures) + _parameters(diag) + full_pose_markdown(diag)
         + _trust(diag) + identification_markdown(diag) + _ranking(diag) + _aliasing(diag)
         + _where(diag.where.nominal, u))
    if diag.where.after_final_model is not None:
        L += _remains(diag.where.after_final_model, u)
    if diag.warnings:
        L.append("\n## Warnings\n")
        L.extend(f"- {_t(m)}" for m in diag.warnings)
    L += ["\n## Method\n", METHOD]
    return "\n".join(L) + "\n"
