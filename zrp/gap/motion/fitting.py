"""Fitting a model of motion effects on top of the registration, re-linearising the
nonlinear effects (Gauss-Newton on the exact model): the static engine's least squares
(:func:`zrp.gap.fit.leastsq.fit`, analytic Jacobian of :class:`zrp.gap.model.problem.Problem`) does
each linear step."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64, I64
from zrp.gap.fit.leastsq import FitResult, fit
from zrp.gap.model.context import EFFECTS, Context, ParamSpec
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem
from zrp.gap.motion.data import Trajectory
from zrp.gap.motion.effects import MotionContext, effect_columns, limit_step, linearise
from zrp.model.manipulator import Manipulator

__all__ = ["Engine", "ModelFit", "named_joints"]

#: samples per block of :meth:`Engine.residual`.
RESIDUAL_BLOCK = 20_000

NONLINEAR = ("sync_delay", "servo_lag", "reversal_friction", "residual_vibration")


@dataclass(frozen=True, eq=False)
class ModelFit:
    """A fitted model: registration + effects.

    Attributes:
        effects: effect name -> the parameter names kept (None: all).
        values: effect parameter name -> value (the last linearisation point = the estimate).
        result: the least-squares fit (registration parameters first).
        ctx: the context of the last linearisation (joint values with the shift).
        iterations: re-linearisations done.
    """

    effects: dict[str, frozenset[str] | None]
    values: dict[str, float]
    result: FitResult
    ctx: Context
    iterations: int

    @property
    def specs(self) -> tuple[ParamSpec, ...]:
        return self.result.specs


def _couplings(traj: Trajectory, effects: Mapping[str, frozenset[str] | None],
               values: Mapping[str, float]) -> dict[str, float]:
    """The sync delay and servo lags of the model that drive a mode through them (eq. M7):
    name -> current value, for the parameters the model keeps."""
    out = {}
    names = ["sync.delay"] + [f"q{k + 1}.lag" for k in range(traj.n_joints)]
    for e, name in zip(["sync_delay"] + ["servo_lag"] * traj.n_joints, names, strict=True):
        keep = effects.get(e, frozenset())
        if e in effects and (keep is None or name in keep):
            out[name] = float(values.get(name, 0.0))
    return out


def named_joints(names: Iterable[str] | None) -> frozenset[int] | None:
    """The 1-based joints of per-joint parameter names ``q{k}.<name>`` (None when ``names`` is
    None or holds a parameter of all joints, e.g. ``sync.delay``): the joints whose columns
    an effect needs to evaluate."""
    if names is None:
        return None
    out = set()
    for name in names:
        head = name.split(".", 1)[0]
        if not (head[:1] == "q" and head[1:].isdigit()):
            return None
        out.add(int(head[1:]))
    return frozenset(out)


def _kept(values: Mapping[str, float], keep: frozenset[str] | None) -> Mapping[str, float]:
    """``values`` without the compliance response's omega and zeta (eq. M8) that the model does
    not keep: the joint is then quasi-static (its column is chosen by the presence of omega)."""
    if keep is None:
        return values
    return {k: v for k, v in values.items()
            if k in keep or not k.endswith((".dyn_omega", ".dyn_zeta"))}


def _dynamic(effects: Mapping[str, frozenset[str] | None], values: Mapping[str, float]) -> bool:
    """Whether the model's compliance has a spring-mass response (eq. M8: nonlinear)."""
    if "dynamic_compliance" not in effects:
        return False
    return any(k.endswith(".dyn_omega") for k in _kept(values, effects["dynamic_compliance"]))


class Engine:
    """The data and registration shared by all fits of one diagnosis.

    Args:
        model: the nominal model.
        traj: the trajectory measurements.
        torque: inverse-dynamics torques (S, n), N m, or None.
        terms: the arm's own stiffness and damping per unit inertia (S, n, 2) for the
            residual vibration (eq. M6), or None.
        reg_specs: registration parameters; base_rotation: R_b0 (3, 3).
    """

    def __init__(self, model: Manipulator, traj: Trajectory, torque: F64 | None,
                 reg_specs: Sequence[ParamSpec], base_rotation: F64,
                 terms: F64 | None = None) -> None:
        self.model = model
        self.traj = traj
        self.torque = torque
        self.terms = terms
        self.meas = traj.measurements
        self.base_ctx = Context(model, self.meas)
        self.reg_specs = tuple(reg_specs)
        self.base_rotation = base_rotation
        #: results that depend on the data only (e.g. the mode responses of the profile search)
        self.cache: dict = {}

    @property
    def nreg(self) -> int:
        return len(self.reg_specs)

    def specs_for(self, effects: Mapping[str, frozenset[str] | None],
                  values: Mapping[str, float]) -> tuple[Context, list[ParamSpec]]:
        """The context (shifted joints) and the effect specs linearised at ``values``."""
        cols = []
        static: list[ParamSpec] = []
        couple = _couplings(self.traj, effects, values)
        for e, keep in effects.items():
            if e in EFFECTS:
                sp, _ = effect_parameters(self.base_ctx, e)
                static += [s for s in sp if keep is None or s.name in keep]
                continue
            vals = values if e != "dynamic_compliance" else _kept(values, keep)
            cols += [c for c in effect_columns(self.traj, e, vals, self.torque,
                                               self.terms, couple, named_joints(keep))
                     if keep is None or (c.via or c.name) in keep]
        shift, mspecs = linearise(cols)
        ctx = MotionContext(self.model, self.meas, shift=shift)
        return ctx, [*mspecs, *static]

    def fit(self, effects: Mapping[str, frozenset[str] | None], poses: I64,
            values: Mapping[str, float] | None = None, reg_theta: F64 | None = None,
            max_outer: int = 6, rtol: float = 1e-3) -> ModelFit:
        """Fit registration + ``effects`` on ``poses`` (sample indices)."""
        vals = dict(values or {})
        reg = np.zeros(self.nreg) if reg_theta is None else np.asarray(reg_theta, float)
        nonlinear = any(e in NONLINEAR for e in effects) or _dynamic(effects, vals)
        it = 0
        while True:
            it += 1
            ctx, specs = self.specs_for(effects, vals)
            theta0 = np.concatenate([reg, [vals.get(s.name, 0.0) for s in specs]])
            res = fit(ctx, [*self.reg_specs, *specs], poses, theta0, self.base_rotation)
            new = {s.name: limit_step(s.name, vals.get(s.name), float(v))
                   for s, v in zip(specs, res.theta[self.nreg:], strict=True)}
            reg = res.theta[:self.nreg]
            se = res.stderr[self.nreg:]
            moved = [abs(new[s.name] - vals.get(s.name, 0.0)) for s in specs]
            done = all(m <= rtol * max(abs(new[s.name]), 0.0) + 0.05 * e
                       for m, s, e in zip(moved, specs, se, strict=True))
            vals = new
            if not nonlinear or done or it >= max_outer:
                return ModelFit(dict(effects), vals, res, ctx, it)

    def residual(self, mf: ModelFit, poses: I64) -> F64:
        """Predicted minus measured on ``poses`` with the fitted model, shape (3R,).

        Increasing ``poses`` are evaluated in blocks of :data:`RESIDUAL_BLOCK` samples (each
        pose's residual is its own, so the values are the same): the model's chain costs
        ~0.5 KB a sample, which on a whole 1e6-sample stream was the diagnosis' peak."""
        poses = np.asarray(poses, dtype=np.int64)
        blocks = ([poses] if poses.size <= RESIDUAL_BLOCK or np.any(np.diff(poses) <= 0)
                  else np.array_split(poses, -(-poses.size // RESIDUAL_BLOCK)))
        return np.concatenate([Problem(mf.ctx, mf.specs, b, self.base_rotation)
                               .residual(mf.result.theta) for b in blocks])
