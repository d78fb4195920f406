"""Full-pose identification: measured orientations (``qw, qx, qy, qz``) beside the positions.

A 6-DOF probe (e.g. a laser tracker's T-Mac) reports the orientation of its own frame in the
instrument frame (base frame for base-frame data). With R_t the constant rotation of the probe
on the hand (registered like the tool offsets), the corrected model predicts

    R_i = R_b R_n(q'_i) R_t,        R_t = exp([psi]) R_t0                               (O1)

(R_b, R_n, q' as in :mod:`zrp.gap.model.problem`). The orientation residual of pose i is the
rotation vector e_i = log(R_i R_meas,i^T) (rad, instrument frame), and for a left
perturbation delta of R_i, de = J_l(e)^-1 delta (J_l: left Jacobian of SO(3)). The perturbation
columns (instrument frame) are

    base rotation phi: J_l(phi);   revolute joint k (dq): R_b u_k B[i, k];                  (O2)
    axis tilt of joint k: R_b omega_k (the omega of the position columns);
    probe rotation psi: R_b R_n J_l(psi);   translations, tool offsets, bodies, thermal: 0.

Identification minimises sum |r_p / sigma_p|^2 + sum |e / sigma_o|^2 (positions per
coordinate, length unit; orientations per component, rad): each block weighted by its own
noise. sigma_p is the position-only fit's residual sigma; sigma_o is given, or estimated from
the orientation residuals (the fit repeated until the estimate settles, 3 passes). The
standard errors are the normal-theory ones of the weighted problem, comparable with the
position-only fit's (the same formula, :func:`zrp.gap.fit.leastsq.fit`).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.constrained import n_registration, sorted_out
from zrp.gap.fit.heldname import tilt_reading
from zrp.gap.fit.leastsq import FitResult, FitWarning, fit, initial_registration
from zrp.gap.fit.orientation import (
    orientation_residual,
    pose_rotations,
    probe_start,
    stacked,
)
from zrp.gap.fit.sumzero import SumZero, expanded, mapped_cov
from zrp.gap.fit.wellposed import HeldDirection, parameter_scales, prior_values, solve
from zrp.gap.model.context import Context, OrientationWeights, ParamSpec
from zrp.gap.model.domains import domain_violations
from zrp.gap.model.problem import Problem

__all__ = ["FullPoseFit", "fit_full_pose", "orientation_residual", "orientation_weights",
           "pose_rotations", "probe_start"]



@dataclass(frozen=True, eq=False)
class FullPoseFit:
    """A full-pose (or, with ``orientation=False``, position-only) fit.

    Attributes:
        specs: the parameters (p); theta: their values (p,); stderr: standard errors (p,).
        probe_rotation: R_t, shape (3, 3) (identity without orientations).
        sigma_position: position noise per coordinate used as weight (length unit).
        sigma_orientation: orientation noise per component (rad; nan without orientations).
        orientation_rms: RMS rotation angle of the orientation residuals (rad; nan without).
        position: the position-only fit (the start).
        orientation: orientations were used.
        sigma_orientation_given: sigma_orientation was given (False: estimated).
        converged, stop_reason, held: the solver's report (:mod:`zrp.gap.fit.wellposed`;
            held: the combinations positions and orientations together cannot pin).
        outside_domain: parameters taken out because their values left their physical
            domains (or lumped weights held at sum 0), with the reasons.
        cov: the covariance of theta (p, p), or None when not kept.
    """

    specs: tuple[ParamSpec, ...]
    theta: F64
    stderr: F64
    probe_rotation: F64
    sigma_position: float
    sigma_orientation: float
    orientation_rms: float
    position: FitResult
    orientation: bool
    sigma_orientation_given: bool = False
    converged: bool = True
    stop_reason: str = ""
    held: tuple[HeldDirection, ...] = ()
    outside_domain: tuple[str, ...] = ()
    cov: F64 | None = None

    def __post_init__(self) -> None:
        p = len(self.specs)
        if self.theta.shape != (p,) or self.stderr.shape != (p,):
            raise InputError("FullPoseFit: theta/stderr do not match the parameters")

    def value(self, name: str) -> float:
        return float(self.theta[self._index(name)])

    def std(self, name: str) -> float:
        return float(self.stderr[self._index(name)])

    def _index(self, name: str) -> int:
        names = [s.name for s in self.specs]
        if name not in names:
            raise InputError(f"name: no parameter {name!r}; fitted: {', '.join(names)}")
        return names.index(name)


def fit_full_pose(ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike, *,
                  orientation: bool = True, orientation_sigma: float | None = None,
                  passes: int = 3) -> FullPoseFit:
    """:func:`_fit_once` inside the physical domains: a parameter whose value leaves its domain
    (:mod:`zrp.gap.model.domains`) is taken out and the rest refitted, and the lumped weights
    of a joint whose sum leaves it are held at sum 0 (:mod:`zrp.gap.fit.sumzero`), as in the
    position fits (:mod:`zrp.gap.fit.constrained`), so the result's ``specs`` may be fewer
    (the reasons are in ``outside_domain``)."""
    reasons: list[str] = []
    held: set[str] = set()
    while True:
        sz = SumZero.of(specs, held)
        fp = _expanded(ctx, sz, _fit_once(ctx, sz.free, poses, orientation=orientation,
                                          orientation_sigma=orientation_sigma, passes=passes))
        first = n_registration(fp.specs)
        bad = domain_violations([x.name for x in fp.specs[first:]],
                                [x.effect for x in fp.specs[first:]],
                                [x.unit for x in fp.specs[first:]], fp.theta[first:],
                                max_tilt_rad=ctx.max_tilt_rad)
        if not bad:
            return dataclasses.replace(fp, outside_domain=tuple(dict.fromkeys(reasons)))
        out, to_hold, why = sorted_out(fp.specs, fp.theta, [(first + i, w) for i, w in bad],
                                       first)
        reasons += why
        held |= to_hold
        specs = [x for i, x in enumerate(fp.specs) if i not in out]


def _expanded(ctx: Context, sz: SumZero, fp: FullPoseFit) -> FullPoseFit:
    """``fp``, a fit of the free coordinates of ``sz``, as a fit of its ``specs``."""
    if not sz.eliminated:
        return fp
    cov = mapped_cov(sz.tied, fp.cov) if fp.cov is not None else None
    se = (np.sqrt(np.clip(np.diag(cov), 0.0, None)) if cov is not None
          else np.full(len(sz.specs), np.nan))
    return dataclasses.replace(fp, specs=sz.specs, theta=sz.theta(fp.theta), stderr=se,
                               position=expanded(ctx, sz, fp.position), cov=cov)


def _fit_once(ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike, *,
              orientation: bool = True, orientation_sigma: float | None = None,
              passes: int = 3) -> FullPoseFit:
    """Identify ``specs`` on ``poses`` from positions and, with ``orientation``, the measured
    orientations, each weighted by its own noise (module doc).

    Args:
        ctx: the data context (its measurements need ``qw..qz`` for ``orientation``).
        specs: registration + effect parameters, as for :func:`zrp.gap.fit.leastsq.fit`.
        poses: pose indices, shape (S,).
        orientation: use the orientations (False: the position-only fit, for comparison).
        orientation_sigma: the orientation noise per component (rad); None: estimated.
        passes: fits with the re-estimated sigma_o (when it is estimated).

    Raises:
        InputError: no orientations, a non-positive sigma, too few poses.
    """
    poses = np.asarray(poses, dtype=np.int64)
    theta0, rb0 = initial_registration(ctx, specs, poses)
    pos = fit(ctx, specs, poses, theta0, rb0, orientation=False)
    sp = pos.sigma
    nan = float("nan")
    if not orientation:
        return FullPoseFit(tuple(specs), pos.theta, pos.stderr, np.eye(3), sp, nan, nan, pos,
                           False, cov=pos.cov)
    if orientation_sigma is not None and not (np.isfinite(orientation_sigma)
                                              and orientation_sigma > 0):
        raise InputError(f"orientation_sigma: expected a positive angle (rad), got "
                         f"{orientation_sigma!r}")
    measured = pose_rotations(ctx)[poses]
    prob = Problem(ctx, specs, poses, rb0)
    rt0 = probe_start(prob, pos.theta, measured)
    p = prob.size
    x = np.concatenate([pos.theta, np.zeros(3)])
    e, _ = orientation_residual(prob, pos.theta, np.zeros(3), rt0, measured)
    so = (float(orientation_sigma) if orientation_sigma is not None
          else float(np.sqrt(np.mean(e ** 2))) or 1e-9)

    def both(v: F64, so: float) -> tuple[F64, F64]:
        return stacked(prob, measured, rt0, sp, so, v)

    start = prob.residual_and_jacobian(pos.theta)[1]
    scales = np.concatenate([parameter_scales(ctx, specs, start), np.ones(3)])
    prior = np.concatenate([prior_values(specs, pos.theta), np.zeros(3)])
    names = [sp_.name for sp_ in specs] + ["probe.rx", "probe.ry", "probe.rz"]
    for _ in range(1 if orientation_sigma is not None else passes):
        sol = solve(lambda v, s=so: both(v, s), lambda v, s=so: both(v, s)[0], x, prior,
                    scales, names)
        x = sol.theta
        e, _ = orientation_residual(prob, x[:p], x[p:], rt0, measured)
        if orientation_sigma is None:
            so = float(np.sqrt(np.sum(e ** 2) / max(e.size - 3, 1))) or 1e-9
    r, J = both(x, so)
    sol = solve(lambda v, s=so: both(v, s), lambda v, s=so: both(v, s)[0], x, prior, scales,
                names, start=(r, J), reading=tilt_reading(ctx, specs, scales))
    x, cov = sol.theta, sol.cov
    if not sol.converged:
        warnings.warn(f"least squares with {len(names)} parameters (full pose): {sol.reason}",
                      FitWarning, stacklevel=2)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))[:p]
    rt = Rotation.from_rotvec(x[p:]).as_matrix() @ rt0
    ang = float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))
    return FullPoseFit(tuple(specs), x[:p], se, rt, sp, so, ang, pos, True,
                       orientation_sigma is not None, sol.converged, sol.reason, sol.held,
                       cov=cov[:p, :p])


def orientation_weights(ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike,
                        orientation_sigma: float | None = None) -> OrientationWeights:
    """The weights with which the orientations enter every fit of a diagnosis: sigma_p and
    sigma_o of the full-pose fit of ``specs`` (the complete geometric calibration, the most
    complete standard model) on ``poses``: sigma_p its position-only residual sigma, sigma_o
    ``orientation_sigma`` when given, else estimated from its orientation residuals (the passes
    of :func:`fit_full_pose`); R_t0 its probe rotation."""
    fp = fit_full_pose(ctx, specs, poses, orientation_sigma=orientation_sigma)
    return OrientationWeights(fp.sigma_position, fp.sigma_orientation, fp.probe_rotation,
                              "given" if orientation_sigma is not None else "estimated")
