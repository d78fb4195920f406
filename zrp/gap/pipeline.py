"""The sim-to-real gap diagnosis: where the gap lies, which effect causes it, how far it shrinks.

Entry point: :func:`diagnose` (in-process; the ``zrp diagnose`` command and the blind benchmark
call it). The stages, in order: check the data and split the poses
(:mod:`zrp.gap.analysis.checks`, :mod:`zrp.gap.data.split`), register (base frame, tool
offsets), estimate the noise floor (:mod:`zrp.gap.data.noise`), analyse where the residual lies
(:mod:`zrp.gap.analysis.where`), survey what the data can identify
(:mod:`zrp.gap.analysis.identifiability`), search the effects (:mod:`zrp.gap.search.greedy`),
judge the final model on the withheld poses. The method and the JSON schema are documented in
zrp/gap/README.md.
"""

from __future__ import annotations

import dataclasses
import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arguments import check_float, check_instance, check_int, check_seed
from zrp.arrays import F64
from zrp.blas import blas_threads
from zrp.errors import InputError
from zrp.gap.analysis.assessment import Assessment, compliance_units, remainder_evidence
from zrp.gap.analysis.baseline import GeometricBaseline, geometric_baseline, geometric_specs
from zrp.gap.analysis.checks import (
    GapWarning,
    check_gravity_torque,
    check_points,
    check_poses,
    check_registration,
    check_units,
)
from zrp.gap.analysis.excitation import excited_only
from zrp.gap.analysis.fallback import FinalChoice, choose_final
from zrp.gap.analysis.identifiability import ReferencePoses, registration_identifiable, survey
from zrp.gap.analysis.notrun import NotRun
from zrp.gap.analysis.residual import fit_residual_model
from zrp.gap.analysis.where import WhereAnalysis, where_analysis
from zrp.gap.data.digest import measurements_sha256
from zrp.gap.data.measurements import Measurements
from zrp.gap.data.noise import noise_floor
from zrp.gap.data.split import split_poses
from zrp.gap.data.subsample import MAX_POINTS, subsample_poses
from zrp.gap.fit.fullpose import orientation_weights
from zrp.gap.fit.leastsq import FitResult, fit, initial_registration
from zrp.gap.fit.metrics import Metrics
from zrp.gap.fit.profiles import with_gravity_side
from zrp.gap.fit.registration import registration_of
from zrp.gap.fit.uncertainty import correlations, interval_covariance, plausibility
from zrp.gap.model.context import EFFECTS, MIN_EXCITATION_RAD, Context
from zrp.gap.model.domains import DEFAULT_MAX_TILT_RAD
from zrp.gap.model.effects import effect_parameters, registration_parameters
from zrp.gap.options import DiagnosisOptions
from zrp.gap.results import UNEXPLAINED_RATIO, Diagnosis, Where
from zrp.gap.search.greedy import SearchSettings, greedy_search, withheld_residual
from zrp.gap.search.posefit import refit_full_pose
from zrp.gap.search.steps import parameter_estimates
from zrp.model.manipulator import Manipulator

__all__ = ["diagnose", "run_diagnosis"]

#: numerical resolution of the fits as a fraction of the model's characteristic length.
RESOLUTION = 1e-9


def diagnose(model: Manipulator, measurements: Measurements, *,
             gravity_torque: ArrayLike | None = None,
             effects: Sequence[str] = EFFECTS,
             rng: np.random.Generator | None = None,
             seed: int = 0,
             withheld_fraction: float = 0.25,
             folds: int = 5,
             alpha: float = 1e-3,
             min_gain: float = 0.01,
             max_steps: int = 4,
             noise_sigma: float | None = None,
             harmonics: tuple[int, ...] = (1, 2),
             gravity_dir: tuple[float, float, float] = (0.0, 0.0, -1.0),
             progress: bool = False,
             max_points: int | None = MAX_POINTS,
             use_orientation: bool = True,
             orientation_sigma: float | None = None,
             max_tilt_rad: float = DEFAULT_MAX_TILT_RAD,
             residual_model: bool = False) -> Diagnosis:
    """Diagnose the gap between ``model`` and ``measurements``.

    Args:
        model: the nominal robot model ("the sim").
        measurements: measured tool points (see :func:`zrp.gap.load_measurements`).
        gravity_torque: the torque gravity exerts on each joint in each pose (positive when
            it turns the joint positively; N m), shape (P, n), in the order of
            ``measurements.pose_ids`` (:func:`mjcf.gravity_torques` computes it from an MJCF
            file with the robot's inertias); without it ``joint_compliance`` identifies a
            lumped-mass model.
        effects: candidate effects (subset of :data:`zrp.gap.EFFECTS`).
        rng: random generator for the split (default ``np.random.default_rng(seed)``).
        seed: seed of the default ``rng``.
        withheld_fraction, folds, alpha, min_gain, max_steps, noise_sigma, harmonics,
            gravity_dir, progress: see :class:`~zrp.gap.options.DiagnosisOptions`.
        max_points: most measured points used; beyond it a seeded random subsample of whole
            poses (the rule in :mod:`zrp.gap.data.subsample`, announced in a warning and in the
            diagnosis's ``warnings``); None uses every point.
        use_orientation: when the measurements carry ``qw..qz``, identify from positions and
            orientations together: every fit of the search and of the geometric baseline
            (each block weighted by its noise, :func:`zrp.gap.fit.fullpose.orientation_weights`),
            then the full-pose refit of the final model (:mod:`zrp.gap.search.posefit`; the
            result's ``full_pose``); False: positions only.
        orientation_sigma: orientation noise per component (rad) weighting the orientation
            residuals; None: estimated from them. Needs measured orientations.
        max_tilt_rad: the largest axis tilt a fitted model may carry (rad; the domain of
            ``axis_misalignment``, :mod:`zrp.gap.model.domains`): widen it for a part known
            to be tilted.
        residual_model: also train a learned residual term after the final model, kept only
            when what remains has structure and the term lowers the withheld error clearly
            (:mod:`zrp.gap.analysis.residual`);
            the final model stays the physical one.

    Returns:
        the :class:`Diagnosis`.

    Raises:
        InputError: too few poses, units that do not fit the model, unidentifiable
            registration, unknown effect names, invalid options (naming the argument).
    """
    check_instance(model, Manipulator, "model", "a zrp.Manipulator (zrp.load_model)")
    check_instance(measurements, Measurements, "measurements",
                   "zrp.gap.Measurements (zrp.load_measurements)")
    check_seed(seed)
    if rng is not None:
        check_instance(rng, np.random.Generator, "rng", "a numpy.random.Generator")
    if isinstance(effects, str):
        raise InputError(f"effects: expected a sequence of effect names, got the string "
                         f"{effects!r}")
    opts = DiagnosisOptions(effects=tuple(effects), withheld_fraction=withheld_fraction,
                            folds=folds, alpha=alpha, min_gain=min_gain, max_steps=max_steps,
                            noise_sigma=noise_sigma, harmonics=tuple(harmonics),
                            gravity_dir=tuple(gravity_dir), progress=progress,
                            max_tilt_rad=max_tilt_rad, residual_model=residual_model)
    if measurements.n_joints != model.n:
        raise InputError(f"{measurements.source}: {measurements.n_joints} joint columns, but "
                         f"the model {model.name!r} has {model.n} joints")
    if max_points is not None:
        check_int(max_points, "max_points", 1)
    _check_orientation(measurements, use_orientation, orientation_sigma)
    rng = np.random.default_rng(seed) if rng is None else rng
    with warnings.catch_warnings(record=True) as wlist:
        warnings.simplefilter("always")
        n_poses = len(measurements.pose_ids)
        digest = measurements_sha256(measurements)  # of the data given, before any subsample
        measurements, kept = subsample_poses(measurements, max_points, seed)
        if kept is not None and gravity_torque is not None:
            gravity_torque = _kept_rows(gravity_torque, kept, n_poses)
        with blas_threads(1):  # small dense problems: one BLAS thread is ~3x faster (zrp.blas)
            result = run_diagnosis(model, measurements, gravity_torque, opts, rng,
                                   use_orientation=bool(use_orientation),
                                   orientation_sigma=orientation_sigma)
            result = _with_full_pose(result, bool(use_orientation), orientation_sigma)
    # raised again, every one at the caller's line (whatever the stage that found it)
    caller = sys._getframe(1)
    for w in wlist:
        warnings.warn_explicit(w.message, w.category, caller.f_code.co_filename,
                               caller.f_lineno)
    caught = tuple(dict.fromkeys(str(w.message) for w in wlist))
    return dataclasses.replace(result, warnings=caught,
                               settings={**result.settings, "measurements_sha256": digest})


def _check_orientation(meas: Measurements, use: object, sigma: object) -> None:
    if not isinstance(use, (bool, np.bool_)):
        raise InputError(f"use_orientation: expected True or False, got {use!r}")
    if sigma is None:
        return
    check_float(sigma, "orientation_sigma", 0.0, 1.0, open_lo=True, unit="rad")
    if meas.quat is None or not use:
        raise InputError("orientation_sigma: given, but " + (
            f"{meas.source} has no qw, qx, qy, qz columns to weight" if meas.quat is None
            else "orientations are switched off: use_orientation=False (--no-orientation on "
            "the command line)"))


def _with_full_pose(diag: Diagnosis, use: bool, sigma: float | None) -> Diagnosis:
    """``diag`` with its final model refitted from positions and orientations when the
    measurements carry them and ``use`` (:mod:`zrp.gap.search.posefit`), recorded in its
    settings."""
    used = use and diag.context.meas.quat is not None
    full = None
    if used:
        ctx, st = diag.context, diag.settings
        cands = {e: excited_only(ctx, effect_parameters(ctx, e))[0] for e in st["effects"]}
        full = refit_full_pose(ctx, diag.final_fit, diag.fitting_poses, diag.withheld_poses,
                               len(diag.registration), sigma, candidates=cands,
                               alpha=st["alpha"], min_gain=st["min_gain"],
                               max_steps=st["max_steps"], nominal=diag.nominal_fit,
                               baseline=None if diag.assessment is None
                               or diag.assessment.baseline.fit is diag.final_fit
                               else diag.assessment.baseline.fit)
    settings = {**diag.settings, "orientation": used, "orientation_sigma_rad": sigma}
    w = diag.context.orientation
    if w is not None:  # the weights every fit of the search and the baseline used
        settings["orientation_weights"] = {"sigma_position": w.sigma_position,
                                           "sigma_orientation_rad": w.sigma_orientation,
                                           "source": w.source}
    return dataclasses.replace(diag, full_pose=full, settings=settings)


def _kept_rows(gravity_torque: ArrayLike, kept: NDArray[np.int64], n_poses: int
               ) -> F64:
    """The rows of the kept poses of a per-pose torque array (its shape is checked later)."""
    tau = np.asarray(gravity_torque, dtype=float)
    if tau.ndim != 2 or tau.shape[0] != n_poses:
        return tau  # wrong shape: reported by the stage that checks it
    return tau[kept]


@dataclass(frozen=True)
class _Prepared:
    """Checked data, the context and the split."""

    ctx: Context
    fitting: NDArray[np.int64]
    withheld: NDArray[np.int64]
    folds: list[NDArray[np.int64]]
    reference: ReferencePoses


@dataclass(frozen=True)
class _Registered:
    """The registration fit, its starting rotation and its errors."""

    fit: FitResult
    rb0: F64
    fitting: Metrics
    withheld_residual: F64


def _prepare(model: Manipulator, meas: Measurements, gravity_torque: ArrayLike | None,
             opts: DiagnosisOptions, rng: np.random.Generator) -> _Prepared:
    check_poses(meas)
    tau = check_gravity_torque(gravity_torque, len(meas.pose_ids), model.n)
    ctx = Context(model, meas, tau, opts.gravity_dir, opts.harmonics,
                  max_tilt_rad=opts.max_tilt_rad)
    fitting, withheld, folds = split_poses(meas, rng, opts.withheld_fraction, opts.folds)
    check_points(meas, fitting)
    check_units(ctx, fitting)
    return _Prepared(ctx, fitting, withheld, folds, ReferencePoses(ctx, rng))


def _register(prep: _Prepared) -> _Registered:
    ctx, fitting = prep.ctx, prep.fitting
    specs = registration_parameters(ctx)
    theta0, rb0 = initial_registration(ctx, specs, fitting)
    specs, theta0 = registration_identifiable(ctx, specs, fitting, theta0, rb0, prep.reference)
    reg = fit(ctx, specs, fitting, theta0, rb0)
    metrics = check_registration(ctx, reg)
    return _Registered(reg, rb0, metrics, withheld_residual(ctx, reg, prep.withheld))


def _split_ids(meas: Measurements, prep: _Prepared, opts: DiagnosisOptions) -> dict:
    pid = meas.pose_ids
    return {"seed_note": "split drawn from the rng passed to diagnose()",
            "withheld_fraction": opts.withheld_fraction,
            "fitting": [pid[i] for i in prep.fitting], "withheld": [pid[i] for i in prep.withheld],
            "folds": [[pid[i] for i in f] for f in prep.folds]}


def _settings(ctx: Context, opts: DiagnosisOptions) -> dict:
    meas = ctx.meas
    return {**opts.settings(), "frame": meas.frame,
            "compliance_model": "mjcf" if ctx.gravity_torque is not None else "lumped_masses",
            "thermal_t_ref_degC": ctx.t_ref, "n_poses": len(meas.pose_ids),
            "n_points": meas.n_rows, "point_labels": list(meas.point_labels)}


def run_diagnosis(model: Manipulator, meas: Measurements, gravity_torque: ArrayLike | None,
                  opts: DiagnosisOptions, rng: np.random.Generator, *,
                  use_orientation: bool = False,
                  orientation_sigma: float | None = None) -> Diagnosis:
    """The stages of :func:`diagnose` (warnings are raised, not collected: ``warnings`` of
    the result is empty). With ``use_orientation`` and measured orientations the search and
    the geometric baseline fit them too (:func:`_with_orientation`)."""
    prep = _prepare(model, meas, gravity_torque, opts, rng)
    regd = _register(prep)
    floor = noise_floor(meas, prep.fitting, opts.noise_sigma)
    where_nominal = where_analysis(prep.ctx, regd.fit)
    ctx, reg = prep.ctx, regd.fit
    if use_orientation and meas.quat is not None:
        ctx, reg = _with_orientation(ctx, reg, prep.fitting, regd.rb0, orientation_sigma)
    if "backlash" in opts.effects and ctx.gravity_torque is None:
        ctx = with_gravity_side(ctx, reg, prep.fitting, regd.rb0, opts.alpha)
    specs_of = {e: effect_parameters(ctx, e) for e in opts.effects}
    identifiability = survey(ctx, reg, specs_of, prep.reference)
    resolution = RESOLUTION * model.characteristic_length
    found = greedy_search(ctx, reg, opts.effects,
                          {e: excited_only(ctx, v) for e, v in specs_of.items()}, SearchSettings(
        prep.fitting, prep.withheld, prep.folds, regd.rb0, opts.alpha, opts.min_gain,
        opts.max_steps, opts.progress, resolution))
    baseline = geometric_baseline(ctx, reg, found.final_fit, prep.fitting, prep.withheld,
                                  prep.folds, regd.rb0)
    final_fit, after, choice = choose_final(ctx, found.final_fit, baseline, prep.withheld)
    if choice.fell_back:  # the search went wrong; a combination is a finding, in the report
        warnings.warn(choice.note(model.length_unit), GapWarning, stacklevel=2)
    final = Metrics.of(after)
    unexplained = (None if floor.rms is None
                   else bool(final.rms > UNEXPLAINED_RATIO * max(floor.rms, resolution)))
    changed = bool(found.steps) or choice.source != "search"
    where = Where(where_nominal, identifiability, found.backlash, found.last_candidates,
                  found.pruned, where_analysis(ctx, final_fit) if changed else None)
    assessment = _assess(ctx, baseline, choice, final_fit, len(reg.specs),
                         where.after_final_model or where_nominal, resolution)
    if opts.residual_model:
        assessment = _with_residual_model(assessment, ctx, final_fit, prep.withheld, after)
    return Diagnosis(model.name, model.length_unit, Metrics.of(regd.withheld_residual),
                     regd.fitting, parameter_estimates(regd.fit, 0), found.steps, final, floor,
                     unexplained, _split_ids(meas, prep, opts), where, found.aliased, (),
                     regd.fit,
                     final_fit, regd.withheld_residual, after, ctx, prep.fitting,
                     prep.withheld, _settings(ctx, opts), assessment)


def _with_residual_model(assessment: Assessment, ctx: Context, final_fit: FitResult,
                         withheld: NDArray[np.int64], after: F64) -> Assessment:
    """The assessment with the learned residual term, or with why it did not run."""
    try:
        rm = fit_residual_model(ctx, final_fit, withheld, after,
                                structure=assessment.remainder.structure)
    except NotRun as exc:
        return dataclasses.replace(assessment, residual_model_not_run=str(exc))
    return dataclasses.replace(assessment, residual_model=rm)


def _with_orientation(ctx: Context, reg: FitResult, fitting: NDArray[np.int64], rb0: F64,
                      sigma: float | None) -> tuple[Context, FitResult]:
    """The context whose fits use the measured orientations (weights from the full-pose fit
    of the complete geometric calibration, :func:`~zrp.gap.fit.fullpose.orientation_weights`)
    and the registration refitted in it (the search's start)."""
    specs = list(reg.specs) + geometric_specs(ctx, reg)
    ctx = dataclasses.replace(ctx, orientation=orientation_weights(ctx, specs, fitting, sigma))
    return ctx, fit(ctx, reg.specs, fitting, reg.theta, rb0)


def _assess(ctx: Context, baseline: GeometricBaseline, choice: FinalChoice, final: FitResult,
            nreg: int, where_final: WhereAnalysis, resolution: float) -> Assessment:
    """Robust intervals, correlations, plausibility, the full registration and the evidence
    on what remains, beside the geometric baseline and the choice of the final model (warns on
    implausible values and on joints the data do not excite)."""
    cov = interval_covariance(ctx, final)  # jackknife over poses, at least the sandwich
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    implausible = tuple(m for i, sp in enumerate(final.specs) if i >= nreg and (
        m := plausibility(sp.name, sp.effect, float(final.theta[i]), float(se[i]), sp.unit)))
    for m in implausible:
        warnings.warn(m, GapWarning, stacklevel=2)
    unexcited = tuple(k + 1 for k in range(ctx.n) if not ctx.excited[k])
    if unexcited:
        warnings.warn(f"joint(s) {', '.join(map(str, unexcited))} move less than "
                      f"{np.degrees(MIN_EXCITATION_RAD):.0f} deg over the poses: these data "
                      "cannot identify an encoder scale, cyclic error or backlash there (none "
                      "is placed on them)", GapWarning, stacklevel=2)
    names = tuple(sp.name for sp in final.specs)
    frame = registration_of(final, se, cov, ctx.meas.point_labels, ctx.model.length_unit)
    return Assessment(baseline, frame, correlations(names, cov), se, implausible, unexcited,
                      remainder_evidence(ctx, final, where_final, resolution), resolution,
                      choice, compliance_units(ctx), _one_sided(ctx))


def _one_sided(ctx: Context) -> tuple[int, ...]:
    """Joints whose MJCF gravity torque keeps one sign (never 0) in every pose."""
    if ctx.gravity_torque is None:
        return ()
    tau = ctx.gravity_side_torque()
    return tuple(k + 1 for k in range(ctx.n)
                 if np.all(tau[:, k] > 0.0) or np.all(tau[:, k] < 0.0))
