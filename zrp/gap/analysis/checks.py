"""Refuse data that cannot give an answer, before and right after the registration.

Each check raises :class:`~zrp.errors.InputError` naming the data source and what to change, or
warns (:class:`~zrp.gap.data.measurements.DataWarning`, :class:`GapWarning`) when the data are
usable but limit what the diagnosis can say.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError, ZRPWarning
from zrp.gap.data.measurements import DataWarning, Measurements
from zrp.gap.data.noise import noise_floor
from zrp.gap.data.split import MIN_POSES
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.metrics import Metrics
from zrp.gap.model.context import Context

__all__ = [
    "GapWarning",
    "check_gravity_torque",
    "check_points",
    "check_poses",
    "check_registration",
    "check_units",
]

#: poses below which effects with many parameters are hard to identify.
FEW_POSES = 50


class GapWarning(ZRPWarning):
    """The diagnosis ran but something limits what it can say (aliasing, poor data...)."""


def check_poses(meas: Measurements) -> None:
    """At least :data:`MIN_POSES` distinct poses; warn about repeats and few poses."""
    P = len(meas.pose_ids)
    n_distinct = int(meas.repeat_groups().max()) + 1
    if P < MIN_POSES or n_distinct < MIN_POSES:
        raise InputError(f"{meas.source}: {P} pose(s), {n_distinct} distinct; the diagnosis "
                         f"needs at least {MIN_POSES} distinct poses (a few hundred for a "
                         "reliable answer)")
    if n_distinct < P:
        warnings.warn(f"{meas.source}: {P - n_distinct} pose(s) repeat the joint values of an "
                      "earlier pose; repeats are kept together in the split and used for the "
                      "noise floor", DataWarning, stacklevel=2)
    if n_distinct < FEW_POSES:
        warnings.warn(f"{meas.source}: only {n_distinct} distinct poses; effects with many "
                      "parameters will be hard to identify", DataWarning, stacklevel=2)


def check_gravity_torque(gravity_torque: ArrayLike | None, n_poses: int, n_joints: int
                         ) -> F64 | None:
    """``gravity_torque`` as finite floats of shape (poses, joints), or None."""
    if gravity_torque is None:
        return None
    tau = np.asarray(gravity_torque, dtype=float)
    if tau.shape != (n_poses, n_joints) or not np.all(np.isfinite(tau)):
        raise InputError(f"gravity_torque: expected finite values of shape ({n_poses}, "
                         f"{n_joints}) (poses x joints), got shape {tau.shape}")
    return tau


#: a tool point must be measured in at least this many poses to locate it on the tool.
MIN_POINT_POSES = 3


def check_points(meas: Measurements, fitting: NDArray[np.int64]) -> None:
    """Every point label is measured in at least :data:`MIN_POINT_POSES` poses and in some
    fitting pose; no two labels are the same point (identical coordinates in every pose)."""
    counts = np.bincount(meas.point_index, minlength=len(meas.point_labels))
    few = [f"{lab} ({c})" for lab, c in zip(meas.point_labels, counts, strict=True)
           if c < MIN_POINT_POSES]
    if few:
        raise InputError(f"{meas.source}: point(s) {', '.join(few)} measured in fewer than "
                         f"{MIN_POINT_POSES} poses; a tool point must be measured in several "
                         "poses to be located (drop it or measure it more)")
    M = len(meas.point_labels)
    pos = np.full((len(meas.pose_ids), M, 3), np.nan)
    pos[meas.pose_index, meas.point_index] = meas.xyz
    tol = 1e-9 * max(float(np.ptp(meas.xyz)), 1e-300)
    for a in range(M):
        for b in range(a + 1, M):
            d = np.linalg.norm(pos[:, a] - pos[:, b], axis=1)
            d = d[np.isfinite(d)]
            if d.size and float(d.max()) <= tol:
                raise InputError(f"{meas.source}: points {meas.point_labels[a]} and "
                                 f"{meas.point_labels[b]} have identical coordinates in every "
                                 "pose: one reflector under two labels? (keep one)")
    seen = meas.point_index[np.isin(meas.pose_index, fitting)]
    missing = [lab for m, lab in enumerate(meas.point_labels) if not np.any(seen == m)]
    if missing:
        raise InputError(f"{meas.source}: point(s) {', '.join(missing)} appear only in withheld "
                         "poses; every point must be measured in several poses")


def check_units(ctx: Context, poses: NDArray[np.int64]) -> None:
    """The measured points and the model's end effector spread alike over ``poses`` (else
    the length unit or the joint-angle unit is wrong)."""
    meas = ctx.meas
    rows = np.isin(meas.pose_index, poses)
    m = meas.xyz[rows]
    p = ctx.nominal_fk.position[meas.pose_index[rows]]
    sm = float(np.sqrt(np.mean(np.sum((m - m.mean(0)) ** 2, axis=1))))
    sp = float(np.sqrt(np.mean(np.sum((p - p.mean(0)) ** 2, axis=1))))
    unit = ctx.model.length_unit
    if sp <= 1e-9 * ctx.model.characteristic_length:
        raise InputError(f"{meas.source}: the end effector hardly moves between the poses "
                         f"(spread {sp:.3g} {unit}); the data cannot be registered (are the "
                         "joint values in degrees? then load them with deg=True)")
    ratio = sm / sp
    if not 1 / 3 < ratio < 3:
        k = math.log10(ratio) if ratio > 0 else 0.0
        hint = (f"; the positions look scaled by 1e{round(k):+03d} (e.g. m instead of mm)"
                if abs(k - round(k)) < 0.2 and abs(round(k)) >= 1 else "")
        raise InputError(
            f"{meas.source}: units do not fit: the measured points spread {sm:.4g} around "
            f"their centre but the model's end effector spreads {sp:.4g} {unit} over the same "
            f"poses (ratio {ratio:.3g}){hint}; x, y, z must be in {unit}, and q in rad (or deg "
            "with deg=True)")


def _noise_explains(ctx: Context, rms: float) -> str | None:
    """A message when the measurement noise, estimated without any model (rigid links or
    repeats), accounts for at least half of a registration error of ``rms`` (3-D RMS)."""
    nf = noise_floor(ctx.meas)
    if nf.sigma is None or math.sqrt(3.0) * nf.sigma < 0.5 * rms:
        return None
    unit = ctx.model.length_unit
    return (f"{ctx.meas.source}: after registration the model misses the measurements by "
            f"{rms:.4g} {unit} RMS, but the measurements themselves scatter that much: the "
            f"noise estimated from the {nf.method.replace('_', ' ')} alone (no model needed) is "
            f"{nf.sigma:.4g} {unit} per coordinate, {math.sqrt(3.0) * nf.sigma:.4g} {unit} per "
            "point; the instrument (or points not rigidly fixed to the tool), not the model, is "
            "at fault, and no diagnosis can see through it")


def check_registration(ctx: Context, reg: FitResult) -> Metrics:
    """The registration is determined and leaves a plausible gap; returns its fitting-set
    errors (warns above 2 % of the reach, raises above 10 %)."""
    meas, model = ctx.meas, ctx.model
    if not np.all(np.isfinite(reg.stderr)):
        bad = [s.name for s, v in zip(reg.specs, reg.stderr, strict=False) if not np.isfinite(v)]
        raise InputError(f"{meas.source}: the registration is not identifiable from these poses "
                         f"({', '.join(bad)} undetermined); the joints must move enough to "
                         "rotate the tool in several directions")
    metrics = Metrics.of(reg.residual)
    unit = model.length_unit
    if metrics.rms > 0.1 * model.characteristic_length:
        noisy = _noise_explains(ctx, metrics.rms)
        if noisy:
            raise InputError(noisy)
        raise InputError(
            f"{meas.source}: after registration the model still misses the measurements by "
            f"{metrics.rms:.4g} {unit} RMS ({100 * metrics.rms / model.reach:.1f} % of the "
            "reach): the model, the joint order/signs or the units (deg=True) do not match the "
            "data")
    if metrics.rms > 0.02 * model.characteristic_length:
        warnings.warn(f"after registration the gap is {metrics.rms:.4g} {unit} RMS, more than "
                      "2 % of the reach: check the model, joint signs and units", GapWarning,
                      stacklevel=2)
    return metrics
