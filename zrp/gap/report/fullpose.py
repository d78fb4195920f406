"""The report's "Full pose" section: what the measured orientations add (the full-pose refit
of :mod:`zrp.gap.fit.fullpose`, beside the position-only estimate)."""

from __future__ import annotations

import math

from scipy.spatial.transform import Rotation

from zrp.escape import md_text as _t
from zrp.gap.report.verdict import full_pose_text
from zrp.gap.results import Diagnosis

__all__ = ["full_pose_markdown"]


def full_pose_markdown(diag: Diagnosis) -> list[str]:
    """The full-pose section (measured orientations), empty without a full-pose fit."""
    fp = diag.full_pose
    if fp is None:
        return []
    u = diag.length_unit
    src = "given" if fp.sigma_orientation_given else "estimated from the residuals"
    rv = Rotation.from_matrix(fp.probe_rotation).as_rotvec()
    b, a = fp.withheld_orientation_before, fp.withheld_orientation_after
    L = ["## Full pose: what the measured orientations add\n",
         full_pose_text(diag) + "\n",
         "The final model (registration included) refitted on the same fitting poses from "
         "positions and orientations, each weighted by its own noise; the withheld poses judge "
         "both estimates (zrp/gap/README.md).\n",
         f"- orientation noise per component: {fp.sigma_orientation:.3g} rad "
         f"({1e3 * fp.sigma_orientation:.3g} mrad), {src}; position noise "
         f"{fp.fit.sigma_position:.4g} {u} per coordinate",
         f"- probe rotation on the hand (rotation vector): [{rv[0]:.5f}, {rv[1]:.5f}, "
         f"{rv[2]:.5f}] rad",
         f"- withheld orientation error (RMS angle): position-only {b:.3g} rad "
         f"({1e3 * b:.3g} mrad), full pose {a:.3g} rad ({1e3 * a:.3g} mrad)",
         f"- withheld position RMS: position-only {fp.withheld_rms_position_only:.4g} {u}, "
         f"full pose {fp.withheld_rms:.4g} {u}\n"]
    if math.isfinite(fp.withheld_orientation_final):
        L.insert(-1, f"- the final model as diagnosed (its fits used the orientations too): "
                     f"withheld orientation error {1e3 * fp.withheld_orientation_final:.3g} "
                     f"mrad beside its withheld position RMS {diag.final.rms:.4g} {u}")
    for a in fp.added:
        L.append(f"Added by the orientation search (score test p = {a.p_value:.2g}, "
                 f"{a.n_tried} groups tried): {a.effect} on joint {a.joint} "
                 f"({', '.join(a.names)}); withheld orientation error "
                 f"{1e3 * a.withheld_orientation_before:.3g} -> "
                 f"{1e3 * a.withheld_orientation_after:.3g} mrad.\n")
    if fp.parameters:
        L += ["| parameter | unit | value (full pose) | std, positions only | std, full pose "
              "| ratio |", "|---|---|---|---|---|---|"]
        L += [f"| {_t(p.name)} | {p.unit} | {p.value:.4g} | {p.std_position_only:.3g} | "
              f"{p.std_full_pose:.3g} | {p.ratio:.2f} |" for p in fp.parameters]
        L.append("")
    return L
