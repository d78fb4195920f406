"""The verdict of a diagnosis in plain words (:func:`verdict_text`, a function of the
:class:`~zrp.gap.Diagnosis`)."""

from __future__ import annotations

import numpy as np

from zrp.gap.analysis.baseline import GeometricBaseline
from zrp.gap.analysis.where import WhereAnalysis
from zrp.gap.fit.constrained import HELD_AT_SUM_0
from zrp.gap.report.headline import effect_joints, headline_text, summary_terminal
from zrp.gap.report.headline import ranges as _ranges
from zrp.gap.results import Diagnosis

__all__ = ["baseline_text", "final_effects_text", "full_pose_text", "remains_text",
           "verdict_sections", "verdict_text"]

#: R^2 below which the residual is said to depend on nothing in particular.
NO_TREND_R2 = 0.1
#: share of the residual common to a pose's points above which it behaves like a positioning
#: error of the robot.
POSE_ERROR_SHARE = 0.8


def _fmt(x: float | None, unit: str) -> str:
    return "n/a" if x is None else f"{x:.4g} {unit}"


def _trend_r2(w: WhereAnalysis) -> tuple[float, float]:
    """The largest R^2 of the residual against one joint angle, and against the measurement
    order, time or temperature."""
    r2_joint = max((j.r2 for j in w.joints), default=0.0)
    r2_other = max([w.order_r2] + [r for r in (w.time_r2, w.temperature_r2) if r is not None])
    return r2_joint, r2_other


def _trend_text(w: WhereAnalysis, r2_joint: float, r2_other: float) -> str:
    """What the residual still depends on, or that it depends on nothing in particular."""
    if r2_joint < NO_TREND_R2 and r2_other < NO_TREND_R2:
        return (f"it depends on no single joint angle, the measurement order, time or "
                f"temperature (R^2 <= {max(r2_joint, r2_other):.2f})")
    j = max(w.joints, key=lambda j: j.r2)
    return (f"it still depends on q{j.joint} (R^2 {j.r2:.2f})" if j.r2 >= r2_other else
            f"it still depends on measurement order/time/temperature (R^2 {r2_other:.2f})")


def _reach_text(w: WhereAnalysis, unit: str) -> str | None:
    """RMS in the inner and the outer third of the reach (None without regions)."""
    regions = w.regions
    inner = [g.rms for g in regions if g is regions[0] or g.radius == regions[0].radius]
    outer = [g.rms for g in regions if g.radius == regions[-1].radius]
    if not (inner and outer):
        return None
    return (f"RMS {np.mean(inner):.3g} {unit} in the inner and {np.mean(outer):.3g} "
            f"{unit} in the outer third of the reach")


def remains_text(w: WhereAnalysis, unit: str) -> str:
    """Plain words on the structure of what remains (from a where analysis)."""
    r2_joint, r2_other = _trend_r2(w)
    no_trend = r2_joint < NO_TREND_R2 and r2_other < NO_TREND_R2
    common = w.common_share
    txt = [] if common is None else [
        f"{100 * common:.0f} % of what remains moves all points of a pose together"]
    txt.append(_trend_text(w, r2_joint, r2_other))
    reach = _reach_text(w, unit)
    if reach is not None:
        txt.append(reach)
    out = "What remains: " + "; ".join(txt) + "."
    if common is not None and common > POSE_ERROR_SHARE and no_trend:
        out += (" No correction of the joint angles or geometry in the library reproduces a "
                "residual of this shape.")
    return out


def final_effects_text(diag: Diagnosis) -> str:
    """The effects of the final model (after the backward pass) with their joints."""
    fj = diag.final_joints
    return ", ".join(effect_joints(e, j) for e, j in fj.items())


def _effects_found(diag: Diagnosis) -> list[str]:
    steps = diag.steps
    choice = None if diag.assessment is None else diag.assessment.choice
    if choice is not None and choice.source != "search":
        found = (f"The search found {', '.join(s.effect for s in steps)}." if steps else
                 "No effect in the library improves the model significantly (none).")
        return [found, choice.note(diag.length_unit),
                f"Final model: {final_effects_text(diag)}."]
    if not steps:
        return ["No effect in the library improves the model significantly (none)."]
    parts = [f"Final model (after pruning): {final_effects_text(diag)}."]
    if choice is not None and choice.note(diag.length_unit):  # an equally good combination
        parts.append(choice.note(diag.length_unit))
    for i, s in enumerate(steps, 1):
        if s.ties:
            parts.append(f"At step {i} {', '.join(s.ties)} explain(s) the data equally well; "
                         f"the data cannot tell {'them' if len(s.ties) > 1 else 'it'} apart "
                         f"from {s.effect}.")
    return parts


def held_names(b: GeometricBaseline) -> str:
    """The parameters of the plain geometric calibration outside their physical domains."""
    return ", ".join(w.split(" = ")[0] for w in b.outside) or "none"


def baseline_text(diag: Diagnosis) -> str:
    """One line: the complete geometric calibration and what the non-geometric effects add
    beyond it on the withheld poses."""
    a = diag.assessment
    if a is None:
        return ""
    b, u = a.baseline, diag.length_unit
    txt = (f"A complete geometric calibration ({b.n_parameters} identifiable kinematic "
           f"parameters, plain least squares) gives {b.withheld.rms:.4g} {u} withheld RMS")
    if b.held is not None:
        txt += (f" (held in the physical domains, which {held_names(b)} left, "
                f"{b.held.rms:.4g} {u})")
    if b.combined is None or b.increment is None:
        return txt + "; the final model adds no non-geometric effect to it."
    verb = "lower" if b.increment > 0 else "raise"
    return (txt + f"; the non-geometric effects ({', '.join(b.non_geometric)}) on top of it "
            f"{verb} that to {b.combined.rms:.4g} {u} ({100 * abs(b.increment):.0f} % "
            f"{'less' if b.increment > 0 else 'more'}).")


def _trust(diag: Diagnosis) -> list[str]:
    a = diag.assessment
    if a is None:
        return []
    parts = []
    if a.implausible:
        names = ", ".join(m.split(" = ")[0] for m in a.implausible)
        parts.append(f"Physically implausible values (do not use them as physical "
                     f"properties): {names}.")
    if (a.compliance is not None and not a.compliance["in_rad_per_newton_metre"]
            and "joint_compliance" in diag.final_joints):
        parts.append(f"Joint compliance is given as compliance x lumped weight in "
                     f"{a.compliance['unit']}, not in rad/(N m): no MJCF supplied the masses.")
    if a.unexcited:
        parts.append(f"These data leave joint(s) {_ranges(a.unexcited)} unidentifiable for "
                     "scale, cyclic error and backlash (they barely move).")
    if a.one_sided:
        parts.append(f"Gravity loads joint(s) {_ranges(a.one_sided)} one way in every pose: a "
                     "play that gravity holds on its loaded flank there shifts the joint by a "
                     "constant, which these data cannot tell from its offset (poses where that "
                     "torque reverses would).")
    return parts


def identification_text(diag: Diagnosis) -> list[str]:
    """What the data could not pin (held at nominal), which effects left their physical
    domains, and any fit that stopped before converging."""
    parts = []
    held = diag.held_directions
    if held:
        shown = "; ".join(h.describe(diag.length_unit) for h in held[:3])
        more = f" and {len(held) - 3} more" if len(held) > 3 else ""
        parts.append(f"{len(held)} parameter combination(s) the data cannot pin stayed at "
                     f"their nominal values: {shown}{more}.")
    loose = [d for d in diag.determination.values() if d.status == "undetermined"]
    if loose:
        names = ", ".join(d.name for d in loose[:4]) + (
            f" and {len(loose) - 4} more" if len(loose) > 4 else "")
        parts.append(f"{len(loose)} parameter(s) the data do not determine (95 % interval wider "
                     f"than the physical domain, or moving the points by more than the error "
                     f"before calibration): {names}; the tables say what each trades "
                     "against.")
    parts += _domain_notes(diag)
    stops = diag.solver_stops
    if stops:
        parts.append(f"{len(stops)} fit(s) stopped before converging ({stops[0]}): their "
                     "values are not at the least-squares minimum.")
    return parts


def _domain_notes(diag: Diagnosis) -> list[str]:
    """Per effect, the first time its values left their physical domains (taken out, or lumped
    weights held at sum 0), while a gap remains: then it says why it was not closed."""
    parts: list[str] = []
    seen: set[str] = set()
    for effect, note in (diag.outside_domain if diag.unexplained is not False else ()):
        if effect in seen:
            continue
        seen.add(effect)
        items = note.split("physical domain: ", 1)[-1].split("; earlier")[0].split("; ")
        why = "; ".join(items[:1] + [i.split(" outside ")[0] for i in items[1:]])
        if note.startswith("fitted values outside"):
            parts.append(f"{effect} was not accepted: fitted to these data it needs values "
                         f"outside its physical domain ({why}); the residual has a shape "
                         "that effect cannot produce physically.")
        elif HELD_AT_SUM_0 in note and "taken out, outside" not in note:
            parts.append(f"{effect}: {why}.")
        else:
            parts.append(f"{effect}: parameters whose fitted values left their physical "
                         f"domain were taken out ({why}).")
    return parts


def _against_floor(diag: Diagnosis) -> list[str]:
    floor, final, unit = diag.noise_floor, diag.final, diag.length_unit
    if floor.rms is None:
        return ["No noise floor can be estimated from these data (one point per pose and no "
                "repeated poses), so whether a gap remains cannot be judged.",
                *_structure_words(diag, always=True)]
    if floor.rms <= (diag.assessment.resolution if diag.assessment else 0.0):
        parts = [f"The noise floor is {floor.rms:.3g} {unit} (noise-free data)."]
        if diag.unexplained:
            parts.append(f"A gap of {final.rms:.4g} {unit} RMS remains.")
        else:
            parts.append("The final model reproduces the data to numerical precision.")
        return parts
    ratio = final.rms / floor.rms
    parts = [f"Noise floor {_fmt(floor.rms, unit)} RMS ({floor.method}); the final error is "
             f"{ratio:.2g}x the floor."]
    if diag.unexplained:
        parts.append(f"A gap of {final.rms:.4g} {unit} RMS remains that no effect in the "
                     "library explains.")
        parts.append(remains_text(diag.where_final, unit))
        parts += _structure_words(diag, always=True)
        parts += _weighed(diag)
    else:
        extra = _structure_words(diag, always=False)
        structured = bool(diag.assessment and diag.assessment.remainder.structure
                          and diag.assessment.remainder.structure.structured)
        parts.append("What remains is close to the noise floor, yet not all scatter."
                     if structured else "What remains is at the noise floor.")
        parts += extra
    return parts


def _structure_words(diag: Diagnosis, *, always: bool) -> list[str]:
    """The multivariate test of what remains in one sentence (``always``: also when it finds
    no structure)."""
    a = diag.assessment
    s = None if a is None else a.remainder.structure
    out = [] if s is None or not (always or s.structured) else [s.words(diag.length_unit)]
    if a is not None and a.remainder.structure_not_run:
        out.append("The multivariate test of what remains did not run: "
                   f"{a.remainder.structure_not_run}.")
    if a is not None and a.residual_model is not None:
        out.append(a.residual_model.words(diag.length_unit))
    if a is not None and a.residual_model_not_run:
        out.append(f"The learned residual term did not run: {a.residual_model_not_run}.")
    return out


def _weighed(diag: Diagnosis) -> list[str]:
    a = diag.assessment
    if a is None:
        return []
    f = a.remainder.findings()
    sup = [e for e, st, _ in f if st == "supported"]
    cant = [e for e, st, _ in f if st == "cannot tell"]
    out = []
    if sup:
        out.append("The data support: " + "; ".join(sup) + ".")
    if cant:
        out.append("They cannot tell: " + "; ".join(cant) + ".")
    if a.remainder.exceeds_spec and a.remainder.repeat_rms is None:
        out.append("A robot pose-to-pose error this large would conflict with the specified "
                   "repeatability of arms of this class (0.01-0.1 mm), so it is not stated as "
                   "the cause; repeated poses would measure it.")
    return out


def full_pose_text(diag: Diagnosis) -> str:
    """One sentence on what the measured orientations add ("" without a full-pose fit)."""
    fp = diag.full_pose
    if fp is None:
        return ""
    src = "given" if fp.sigma_orientation_given else "estimated"
    best = fp.best
    std = ("no effect parameter to compare" if best is None else
           f"effect-parameter standard errors x{fp.std_ratio_median:.2f} of the position-only "
           f"fit (median; {best.name} x{best.ratio:.2f})")
    reveal = "".join(f" Orientations reveal {a.effect} (joint {a.joint}; p = {a.p_value:.2g}), "
                     "which positions see weakly." for a in fp.added)
    nominal = ("" if not np.isfinite(fp.withheld_orientation_nominal) else
               f"{1e3 * fp.withheld_orientation_nominal:.3g} mrad after registration, ")
    base = ("" if fp.baseline_withheld is None else
            f" (the complete geometric calibration from positions and orientations: "
            f"{1e3 * fp.baseline_withheld[0]:.3g} mrad, {fp.baseline_withheld[1]:.4g} "
            f"{diag.length_unit})")
    final = ("" if not np.isfinite(fp.withheld_orientation_final) else
             f" The final model, whose fits used the orientations too: "
             f"{1e3 * fp.withheld_orientation_final:.3g} mrad withheld orientation error, "
             f"{diag.final.rms:.4g} {diag.length_unit} withheld position RMS.")
    return (f"Measured orientations (noise {1e3 * fp.sigma_orientation:.3g} mrad, {src}) "
            f"add: {std}; withheld orientation error {nominal}"
            f"{1e3 * fp.withheld_orientation_before:.3g} -> "
            f"{1e3 * fp.withheld_orientation_after:.3g} mrad, withheld position RMS "
            f"{fp.withheld_rms_position_only:.4g} -> {fp.withheld_rms:.4g} {diag.length_unit}"
            f"{base}." + reveal + final)


def verdict_sections(diag: Diagnosis) -> list[tuple[str, str]]:
    """The details under the headline, as (title, paragraph): the effects found and how far
    the withheld error shrinks beside the geometric calibration; what remains against the
    noise floor (with the weighed evidence on an unexplained remainder); what the data could
    not pin; what not to trust; what measured orientations add. Empty sections are left
    out."""
    nominal, final, unit = diag.nominal, diag.final, diag.length_unit
    shrunk = 100 * (1 - final.rms / nominal.rms) if nominal.rms > 0 else 0
    found = _effects_found(diag)
    found.append(f"Withheld RMS {nominal.rms:.4g} {unit} after registration, "
                 f"{final.rms:.4g} {unit} with the final model ({shrunk:.0f} % smaller).")
    bl = baseline_text(diag)
    if bl:
        found.append(bl)
    out = [("Effects found", found), ("What remains", _against_floor(diag)),
           ("What the data cannot pin", identification_text(diag)),
           ("What not to trust", _trust(diag)),
           ("Measured orientations", [full_pose_text(diag)] if diag.full_pose else [])]
    return [(title, " ".join(parts)) for title, parts in out if parts]


def verdict_text(diag: Diagnosis) -> str:
    """The verdict for the terminal and diagnosis.json: the headline (at most 80 words,
    :func:`~zrp.gap.report.headline.headline_text`), the table of withheld errors, then the
    details, each section a titled paragraph (:func:`verdict_sections`), separated by blank
    lines."""
    blocks = [headline_text(diag), summary_terminal(diag)]
    blocks += [f"{title}:\n{text}" for title, text in verdict_sections(diag)]
    return "\n\n".join(blocks)
