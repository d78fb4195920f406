"""FIGAROH's geometric calibration (PyPI ``figaroh``, on Pinocchio) as a timing peer of the
gap diagnosis, on the same measurements and the same nominal model.

What runs is FIGAROH's own chain (:class:`figaroh.calibration.base_calibration.
BaseCalibration`): ``initialize()`` (reads the CSV, builds the full-parameter list: 6
corrections per joint, the unknown base frame and one tip frame per marker, and drops what its
structural QR and the frame absorption find unidentifiable) and ``solve()`` (SciPy's
Levenberg-Marquardt with its outlier loop, then its evaluation and quality report). The cost is
the one FIGAROH's docstring gives as the example: its updated forward kinematics
(``calc_updated_fkm``) and the SE(3) log-map residuals in the world frame, weighted by the
noise (``apply_measurement_weighting``): positions per millimetre-level noise, orientations per
their noise.

The robot is the model's own URDF (:func:`zrp.model.urdf_writer.save_urdf`, lengths in
metres); the measurements become FIGAROH's CSV (``x1, y1, z1[, phix1..phiz1], x2, ...`` in
metres and roll-pitch-yaw, one column per joint), written before the clock starts: what is
timed is ``initialize() + solve()``, as a user runs it on a file. The fit's RMS over all
poses (FIGAROH fits them all; the diagnosis holds a quarter out) is returned to show that it
converged, not as an accuracy comparison.
"""

from __future__ import annotations

import contextlib
import io
import logging
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

import zrp
from zrp.gap import Measurements
from zrp.model.urdf_writer import save_urdf
from zrp.units import metres_per_unit

__all__ = ["figaroh_available", "figaroh_calibration"]


def figaroh_available() -> str | None:
    """None when FIGAROH and Pinocchio import, else why not."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import figaroh.calibration.base_calibration  # noqa: F401
            import pinocchio  # noqa: F401
    except ImportError as exc:
        return f"not installed ({exc})"
    return None


_CONFIG = """\
meta:
  schema_version: "2.0"
robot:
  name: {name}
tasks:
  calibration:
    type: kinematic_calibration
    kinematics:
      base_frame: universe
      tool_frame: tool
    measurements:
      markers:
{markers}
    parameters:
      calibration_level: full_params
      include_non_geometric: false
      outlier_threshold: 1.0
    data:
      number_of_samples: {samples}
      source_file: {data}
"""


def _csv(model: zrp.Manipulator, meas: Measurements, path: Path, orientation: bool) -> int:
    """FIGAROH's CSV of ``meas`` (every pose with all its points); the number of markers."""
    scale = metres_per_unit(model.length_unit)
    labels = meas.point_labels
    P, M = len(meas.pose_ids), len(labels)
    xyz = np.full((P, M, 3), np.nan)
    xyz[meas.pose_index, meas.point_index] = np.asarray(meas.xyz) * scale
    keep = np.all(np.isfinite(xyz.reshape(P, -1)), axis=1)
    cols, data = [], []
    for m in range(M):
        cols += [f"x{m + 1}", f"y{m + 1}", f"z{m + 1}"]
        data.append(xyz[keep, m])
        if orientation:
            q = np.asarray(meas.quat)[meas.first_row][keep]
            rpy = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_euler("xyz")  # pin.rpy order
            cols += [f"phix{m + 1}", f"phiy{m + 1}", f"phiz{m + 1}"]
            data.append(rpy)
    cols += list(model.joint_names)
    data.append(np.asarray(meas.q_pose)[keep])
    table = np.hstack(data)
    lines = [",".join(cols)] + [",".join(repr(float(v)) for v in row) for row in table]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return M


def _limited(model: zrp.Manipulator) -> zrp.Manipulator:
    """``model`` with +-2 pi limits on joints that have none: an unlimited URDF joint is
    ``continuous``, which Pinocchio stores as (cos q, sin q), two numbers, and FIGAROH reads
    one column per joint. The kinematics are the same."""
    limits = [j.limits if j.limits is not None else (-2 * np.pi, 2 * np.pi)
              for j in model.joints]
    return zrp.Manipulator.from_arrays(model.axes, model.bodies,
                                       axial=model.end_effector.axial,
                                       transverse=model.end_effector.transverse,
                                       limits=limits, name=model.name)


def _calibration_class(sigma_position: float, sigma_orientation: float) -> type:
    from figaroh.calibration.base_calibration import BaseCalibration
    from figaroh.calibration.calibration_tools import (
        calc_updated_fkm,
        estimate_frames_closed_form,
    )

    class Calibration(BaseCalibration):  # type: ignore[misc]
        """FIGAROH's documented cost: updated FK, SE(3) log-map residuals (world-frame
        positions), weighted by the noise; the base and tip frames unknown (as FIGAROH's
        own robot examples set them)."""

        def __init__(self, robot: Any, config_file: str) -> None:
            super().__init__(robot, config_file)
            self.calib_config["known_baseframe"] = False
            self.calib_config["known_tipframe"] = False

        def initial_frame_guess(self) -> dict[str, float]:
            """FIGAROH's closed form on the positions; with orientations, the tip rotation
            then the chordal mean of R_i^T R_b^T R_meas (its closed form with orientations
            started a probe turned by 2.8 rad in a wrong basin: 666 mm RMS after solve)."""
            cfg = self.calib_config
            if all(cfg["measurability"][3:6]):
                return self._with_orientation_guess()
            return super().initial_frame_guess()

        def _with_orientation_guess(self) -> dict[str, float]:
            import pinocchio as pin

            cfg = self.calib_config
            n = len(self.q_measured)
            M = np.asarray(self.PEE_measured).reshape(1, 6, n)
            pos_cfg = dict(cfg, measurability=[True, True, True, False, False, False])
            guess = estimate_frames_closed_form(self.model, self.data, self.q_measured,
                                                M[:, :3].ravel(), pos_cfg)
            base = np.array([guess.get(k, 0.0) for k in ("base_phix", "base_phiy",
                                                         "base_phiz")])
            rb = pin.rpy.rpyToMatrix(base)
            fid = self.model.getFrameId(cfg["end_frame"])
            acc = np.zeros((3, 3))
            for i in range(n):
                pin.framesForwardKinematics(self.model, self.data, self.q_measured[i])
                ri = self.data.oMf[fid].rotation
                acc += ri.T @ rb.T @ pin.rpy.rpyToMatrix(M[0, 3:6, i])
            u, _, vt = np.linalg.svd(acc)
            tip = pin.rpy.matrixToRpy(u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt)
            names = cfg["param_name"]
            guess.update({k: float(v) for k, v in zip(("phiEEx_1", "phiEEy_1", "phiEEz_1"),
                                                      tip, strict=True) if k in names})
            return guess

        def cost_function(self, var: np.ndarray) -> np.ndarray:
            est = calc_updated_fkm(self.model, self.data, var, self.q_measured,
                                   self.calib_config)
            res = self._compute_logmap_residuals(self.PEE_measured, est,
                                                 position_frame="world")
            return self.apply_measurement_weighting(res, pos_weight=1.0 / sigma_position,
                                                    orient_weight=1.0 / sigma_orientation)

    return Calibration


def figaroh_calibration(model: zrp.Manipulator, meas: Measurements, *,
                        orientation: bool, sigma_position_m: float = 1e-4,
                        sigma_orientation: float = 1e-4
                        ) -> tuple[Callable[[], dict[str, Any]], Callable[[], None]]:
    """A call that runs FIGAROH's ``initialize()`` + ``solve()`` on ``meas`` (files written
    now, in a temporary folder), and the call that removes that folder.

    The run returns ``{"rms_mm": fit RMS of the positions over all poses, "parameters":
    how many it estimated, "converged": bool}``.
    """
    from figaroh.tools.load_robot import load_robot

    work = Path(tempfile.mkdtemp(prefix="zrp-figaroh-"))
    urdf = save_urdf(_limited(model), work / "robot.urdf")
    n_markers = _csv(model, meas, work / "data.csv", orientation)
    dof = "[true, true, true, true, true, true]" if orientation else \
        "[true, true, true, false, false, false]"
    markers = "\n".join(f"        - ref_joint: tool_joint\n          measurable_dof: {dof}"
                        for _ in range(n_markers))
    config = work / "config.yaml"
    config.write_text(_CONFIG.format(name="robot", markers=markers, data=work / "data.csv",
                                     samples=len(meas.pose_ids)), encoding="utf-8")
    cls = _calibration_class(sigma_position_m, sigma_orientation)
    scale = 1e3  # m -> mm for the reported RMS

    def run() -> dict[str, Any]:
        logging.disable(logging.INFO)
        try:  # its quality report goes to stdout: not shown
            with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
                warnings.simplefilter("ignore")
                robot = load_robot(str(urdf))
                cal = cls(robot, str(config))
                cal.initialize()
                res = cal.solve(enable_logging=False)
        finally:
            logging.disable(logging.NOTSET)
        est = cal.get_pose_from_measure(res.x)
        n_meas = 6 if orientation else 3
        S = cal.calib_config["NbSample"]
        d = (est - cal.PEE_measured).reshape(n_markers, n_meas, S)[:, :3]
        rms = float(np.sqrt(np.mean(np.sum(d**2, axis=1)))) * scale
        return {"rms_mm": rms, "parameters": len(res.x), "converged": bool(res.success)}

    def cleanup() -> None:
        for p in work.iterdir():
            p.unlink()
        work.rmdir()

    return run, cleanup
