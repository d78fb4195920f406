"""The fleet diagnosis's unit of work: one robot's measurement file, diagnosed wherever a worker
runs it, its outputs written into its own folder, and a short summary row sent back."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from zrp.model.manipulator import Manipulator

__all__ = ["RobotTask", "diagnose_robot", "robot_row"]


@dataclass(frozen=True)
class RobotTask:
    """One robot of the fleet (picklable; the worker must see ``data`` and ``out``).

    Attributes:
        name: the robot's name (the file's stem; unique in the fleet).
        data: its measurement CSV.
        out: its output folder (diagnosis.json, report.md, residuals.csv, plots).
        model: the nominal model; mjcf: the MJCF with inertias, or None.
        read: keyword arguments of :func:`zrp.gap.load_measurements` (deg, frame).
        options: keyword arguments of :func:`zrp.gap.diagnose`.
        plots: write the per-robot plots.
    """

    name: str
    data: Path
    out: Path
    model: Manipulator
    mjcf: Path | None = None
    read: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    plots: bool = True

    def __str__(self) -> str:
        return f"{self.name} ({self.data})"


def robot_row(name: str, data: str, d: dict[str, Any]) -> dict[str, Any]:
    """The fleet table's row of one robot from its diagnosis.json document."""
    steps = d.get("steps") or []
    joints = {e["effect"]: e["joints"] for e in d["final"].get("effects", [])}
    top = d["effects"][0] if d.get("effects") else "none"
    if (d.get("final_model") or {}).get("fell_back") and steps:
        joints = {top: steps[0].get("joints", [])}  # final = the geometric calibration: the
        # joints the search named (zrp/gap/analysis/fallback.py)
    return {"robot": name, "data": data, "points": d["nominal"]["n_points"],
            "error_rms": d["nominal"]["rms"], "error_p95": d["nominal"]["p95"],
            "error_max": d["nominal"]["max"], "corrected_rms": d["final"]["rms"],
            "corrected_max": d["final"]["max"], "shrink": d["final"]["shrink"],
            "top_effect": top, "top_joints": joints.get(top, []),
            "effects": list(d.get("effects", [])), "steps": len(steps),
            "noise_rms": d["noise_floor"].get("rms"), "unexplained": d.get("unexplained")}


def diagnose_robot(task: RobotTask) -> dict[str, Any]:
    """Load, diagnose, write the robot's report; return its :func:`robot_row`."""
    # mjcf loads MuJoCo: only in a fleet run that was given an MJCF
    from mjcf.gravity import gravity_torques
    from zrp.gap import diagnose, load_measurements  # on use: keeps --help quick
    from zrp.gap.report import diagnosis_document, write_outputs  # on use: keeps --help quick

    meas = load_measurements(task.data, task.model, **task.read)
    tau = None if task.mjcf is None else gravity_torques(
        task.mjcf, meas.q_pose, field="--mjcf", joint_names=[j.name for j in task.model.joints])
    with warnings.catch_warnings(record=True):  # kept in the diagnosis's own warnings list
        warnings.simplefilter("always")
        diag = diagnose(task.model, meas, gravity_torque=tau, **task.options)
    write_outputs(diag, task.out, overwrite=True, plots=task.plots)
    return robot_row(task.name, str(task.data), diagnosis_document(diag))
