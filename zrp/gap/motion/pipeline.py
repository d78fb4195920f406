"""``diagnose_motion``: the stages of the motion diagnosis in order.

register (on the fitting segments) -> greedy search over motion effects (on a decimated copy
of the fitting samples: at 1 kHz neighbouring samples add little information but cost time)
-> backward check -> final fit on all fitting samples -> withheld time segments, phases, noise.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64, I64
from zrp.blas import blas_threads
from zrp.errors import InputError
from zrp.gap.fit.aliasing import ALIAS_TOL
from zrp.gap.fit.leastsq import initial_registration, point_errors
from zrp.gap.fit.metrics import Metrics
from zrp.gap.model.context import EFFECTS, Context
from zrp.gap.model.effects import registration_parameters
from zrp.gap.model.problem import Problem
from zrp.gap.motion.data import Trajectory, check_rate
from zrp.gap.motion.effects import MOTION_EFFECTS
from zrp.gap.motion.fitting import Engine, ModelFit
from zrp.gap.motion.results import MotionDiagnosis, MotionEstimate, MotionStep, PhaseError
from zrp.gap.motion.search import backward_check, drop_effects, greedy, settle_compliance
from zrp.gap.motion.segments import PHASES, phases, split_segments, stream_noise_sigma
from zrp.model.manipulator import Manipulator

__all__ = ["diagnose_motion"]



def _check(model: Manipulator, traj: Trajectory, torque: ArrayLike | None,
           effects: Sequence[str]) -> F64 | None:
    if not isinstance(traj, Trajectory):
        raise InputError(f"trajectory: expected a zrp.gap.motion.Trajectory, got "
                         f"{type(traj).__name__}")
    check_rate(traj.t, traj.lines, traj.source)
    if traj.n_joints != model.n:
        raise InputError(f"trajectory has {traj.n_joints} joint columns but the model "
                         f"{model.name!r} has {model.n} joints")
    for e in effects:
        if e not in MOTION_EFFECTS + EFFECTS:
            raise InputError(f"effects: {e!r} is not an effect; valid: "
                             f"{', '.join(MOTION_EFFECTS + EFFECTS)}")
    if torque is None:
        return None
    tau = np.asarray(torque, dtype=float)
    if tau.shape != traj.q.shape or not np.all(np.isfinite(tau)):
        raise InputError(f"torque: expected finite values of shape {traj.q.shape} (N m), got "
                         f"{tau.shape}")
    return tau


def _check_terms(traj: Trajectory, terms: ArrayLike | None) -> F64 | None:
    if terms is None:
        return None
    a = np.asarray(terms, dtype=float)
    if a.shape != (*traj.q.shape, 2) or not np.all(np.isfinite(a)):
        raise InputError(f"mode_terms: expected finite values of shape "
                         f"{(*traj.q.shape, 2)} (stiffness 1/s^2, damping 1/s per unit "
                         f"inertia, mjcf.mode_terms), got {a.shape}")
    return a


def _registration(ctx: Context, poses: I64) -> tuple[list, F64, F64]:
    """Registration parameters these samples can identify (Gram-Schmidt on the normalised
    Jacobian columns, as :func:`zrp.gap.fit.leastsq.check_identifiable`), starting values, R_b0."""
    specs = registration_parameters(ctx)
    theta0, rb0 = initial_registration(ctx, specs, poses)
    _, J = Problem(ctx, specs, poses, rb0).residual_and_jacobian(theta0)
    keep: list[int] = []
    basis = np.zeros((J.shape[0], 0))
    for i in range(J.shape[1]):
        c = J[:, i] / max(np.linalg.norm(J[:, i]), 1e-300)
        r = c - basis @ (basis.T @ c)
        if specs[i].kind == "tool" and np.linalg.norm(r) < ALIAS_TOL * 1e3:
            continue  # the base frame always stays (the Problem needs all six)
        keep.append(i)
        basis = np.column_stack([basis, r / np.linalg.norm(r)])
    return [specs[i] for i in keep], theta0[keep], rb0


def _decimate(idx: I64, limit: int) -> I64:
    step = max(1, int(np.ceil(idx.size / limit)))
    return idx[::step]


def _estimates(eng: Engine, mf: ModelFit) -> tuple[MotionEstimate, ...]:
    se = mf.result.stderr
    return tuple(MotionEstimate(s.name, s.effect, s.joint, s.unit, float(mf.result.theta[i]),
                                float(se[i]))
                 for i, s in enumerate(mf.specs) if i >= eng.nreg)


def _phase_table(traj: Trajectory, before: F64, after: F64, withheld: I64) -> tuple:
    masks = phases(traj).masks
    held = np.zeros(traj.n_samples, dtype=bool)
    held[withheld] = True

    def rms(e: F64, m: NDArray[np.bool_]) -> float | None:
        return float(np.sqrt(np.mean(e[m] ** 2))) if m.any() else None

    out = []
    for name in PHASES:
        m = masks[name]
        out.append(PhaseError(name, int(m.sum()), rms(before, m), rms(after, m),
                              rms(before, m & held), rms(after, m & held)))
    return tuple(out)


def _one_blas_thread(fn: Callable[..., MotionDiagnosis]) -> Callable[..., MotionDiagnosis]:
    """Run ``fn`` with one BLAS thread, as the static diagnosis does (:mod:`zrp.blas`: many
    small dense problems; OpenBLAS threads spin against each other under load)."""

    @functools.wraps(fn)
    def run(*args: Any, **kwargs: Any) -> MotionDiagnosis:
        with blas_threads(1):
            return fn(*args, **kwargs)

    return run


@_one_blas_thread
def diagnose_motion(model: Manipulator, trajectory: Trajectory, *,
                    torque: ArrayLike | None = None, mode_terms: ArrayLike | None = None,
                    effects: Sequence[str] = MOTION_EFFECTS,
                    rng: np.random.Generator | None = None, seed: int = 0,
                    withheld_fraction: float = 0.25, n_segments: int = 20, folds: int = 5,
                    alpha: float = 1e-3, max_steps: int = 3, noise_sigma: float | None = None,
                    max_search_samples: int = 2500, max_fit_samples: int = 20000
                    ) -> MotionDiagnosis:
    """Diagnose the sim-to-real gap along a measured trajectory.

    Args:
        model: the nominal model ("sim": the commanded joints through its kinematics).
        trajectory: the time-stamped measurements.
        torque: inverse-dynamics torque per sample and joint (N m), shape (S, n), from the
            MJCF inertias (``mjcf.inverse_dynamics_torques``); enables ``dynamic_compliance``.
        mode_terms: the arm's own stiffness (1/s^2) and damping (1/s) of each joint per unit
            inertia along the commanded path, shape (S, n, 2), from the MJCF
            (``mjcf.mode_terms``); the residual vibration's mode then carries them (eq. M6:
            gravity's stiffness and the velocity coupling change the mode along the path).
        effects: candidates (motion effects, static ones allowed too).
        rng: seeded generator of the segment split (default: from ``seed``).
        withheld_fraction, n_segments, folds: the split by time segments.
        alpha: significance level of adding an effect.
        max_steps: most effects added.
        noise_sigma: known tracker noise per coordinate (length unit); default: estimated from
            second differences of the stream.
        max_search_samples: at most this many fitting samples are used by the search (evenly
            decimated: at 1 kHz neighbouring samples carry nearly the same information).
        max_fit_samples: at most this many fitting samples enter the final fit (evenly
            decimated); the withheld errors are computed on every withheld sample.
    """
    clock = {"start": time.perf_counter()}
    tau = _check(model, trajectory, torque, effects)
    terms = _check_terms(trajectory, mode_terms)
    rng = np.random.default_rng(seed) if rng is None else rng
    split = split_segments(trajectory, rng, n_segments, withheld_fraction, folds)
    search = _decimate(split.fitting, max_search_samples)
    sfolds = [np.intersect1d(f, search) for f in split.folds]
    ctx = Context(model, trajectory.measurements)
    reg_specs, reg0, rb0 = _registration(ctx, search)
    eng = Engine(model, trajectory, tau, reg_specs, rb0, terms)
    start = eng.fit({}, search, reg_theta=reg0)
    clock["register"] = time.perf_counter()
    final, trace = greedy(eng, start, list(effects), search, sfolds, alpha, 0.01, max_steps)
    final = drop_effects(eng, backward_check(eng, final, search, alpha), search, alpha)
    final = settle_compliance(eng, final, search)
    clock["search"] = time.perf_counter()
    fitting = _decimate(split.fitting, max_fit_samples)
    nominal = eng.fit({}, fitting, reg_theta=start.result.theta)
    final_all = settle_compliance(eng, eng.fit(final.effects, fitting, final.values,
                                               final.result.theta[:eng.nreg]), fitting)
    clock["final_fit"] = time.perf_counter()
    steps = []
    for tr, ranked in trace:
        if tr.fit is None or tr.effect not in final_all.effects:
            continue
        ties = tuple(r.effect for r in ranked[1:]  # untried: cv_rms = inf
                     if r.cv_rms <= 1.01 * tr.cv_rms)
        steps.append(MotionStep(tr.effect, tr.joints, tr.cv_rms, tr.p_value, tr.bic_delta,
                                Metrics.of(eng.residual(tr.fit, split.withheld)),
                                tuple(r.to_dict() for r in ranked), ties))
    every = np.arange(trajectory.n_samples)
    m = len(trajectory.point_labels)
    r_before = eng.residual(nominal, every).reshape(-1, m, 3)
    r_after = eng.residual(final_all, every).reshape(-1, m, 3)
    e_before = point_errors(r_before.ravel()).reshape(-1, m).mean(axis=1)
    e_after = point_errors(r_after.ravel()).reshape(-1, m).mean(axis=1)
    if noise_sigma is None:
        sigma, _ = stream_noise_sigma(trajectory)
        method = "second_differences"
    else:
        sigma, method = float(noise_sigma), "given"
    clock["end"] = time.perf_counter()
    warn = []
    if len(reg_specs) < len(registration_parameters(ctx)):
        warn.append("some registration parameters cannot be identified from this path "
                    "(e.g. tool offsets with a constant hand orientation); they are fixed")
    return MotionDiagnosis(
        model.name, model.length_unit,
        {"effects": list(effects), "alpha": alpha, "max_steps": max_steps,
         "n_segments": n_segments, "folds": folds, "withheld_fraction": withheld_fraction,
         "n_samples": trajectory.n_samples, "rate_hz": trajectory.rate_hz,
         "duration_s": trajectory.duration, "search_samples": int(search.size),
         "fit_samples": int(fitting.size),
         "torque": tau is not None, "mode_terms": terms is not None,
         "point_labels": list(trajectory.point_labels)},
        Metrics.of(r_before[split.withheld].ravel()), tuple(steps),
        Metrics.of(r_after[split.withheld].ravel()), _estimates(eng, final_all), sigma,
        method, _phase_table(trajectory, e_before, e_after, split.withheld),
        {"withheld_segments": list(split.withheld_segments),
         "n_fitting": int(split.fitting.size), "n_withheld": int(split.withheld.size)},
        {k: clock[k] - clock["start"] for k in ("register", "search", "final_fit", "end")},
        trajectory.xyz + r_before, trajectory.xyz + r_after, tuple(warn),
        Problem(final_all.ctx, final_all.specs, fitting, rb0).base(final_all.result.theta))
