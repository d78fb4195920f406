"""The learned residual term in the calibration files (zrp/calibration/learned.py, issue 36).

A simulated IRB 120 whose tool points sag by ``sag sin(q2) cos(q3)`` (zrp/gap/data/synthetic.py:
no effect of the library has this shape) is calibrated with ``residual_model=True``. The term
the diagnosis keeps goes into compensation.json as plain arrays; read back, it evaluates as
the diagnosis's own kernel (scikit-learn's RBF kernel: an independent reference for the plain
NumPy evaluation of the file). Compensated with it, the arm lands closer to its targets on
the noise-free synthetic truth than with the physical model alone; targets outside its
training ranges are refused (or flagged with accept_flagged); a field outside its domain is
refused on read. On pose-to-pose scatter no term is kept and the files carry none."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

from zrp.calibration import CalibrationOptions, calibrate, compensate, read_calibration
from zrp.calibration.calibrated import rotation_about
from zrp.calibration.filecheck import FieldDomainError
from zrp.calibration.guards import UnmeasuredTargetError
from zrp.gap import Injection, Measurements, synthesize
from zrp.kinematics import uniform_joint_values

from ..gap.test_recovery import IRB120, LIMITS
from .pairs import write_bound

SIGMA = 0.02  # mm per coordinate
SAG = Injection(sag=0.15, joint_offset={2: 5e-4})


def _measure(injection, seed, poses, scatter=0.0):
    rng = np.random.default_rng(seed)
    q = uniform_joint_values(IRB120, poses, rng, LIMITS["irb120"])
    meas = synthesize(IRB120, q, injection, rng=rng, noise_sigma=SIGMA)
    if scatter:  # a shift of the whole tool per pose that no joint angle predicts
        shift = np.repeat(rng.normal(scale=scatter, size=(poses, 3)), 3, axis=0)
        meas = Measurements.from_arrays(meas.pose, meas.q, meas.xyz + shift, point=meas.point)
    return meas


def _calibrate(meas):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(IRB120, meas, options=CalibrationOptions(residual_model=True))


@pytest.fixture(scope="module")
def sag(tmp_path_factory):
    """The sag arm calibrated with its learned term, written and read back."""
    res = _calibrate(_measure(SAG, seed=11, poses=500))
    folder = tmp_path_factory.mktemp("learned")
    res.write(folder / "calibrated.toml", folder / "compensation.json")
    return res, folder, read_calibration(folder / "compensation.json")


def _inside(cal, count, seed):
    """Joint vectors inside the learned term's training ranges (and the measured ones)."""
    rng = np.random.default_rng(seed)
    lim = np.array(cal.conditions.joint_ranges)
    q = uniform_joint_values(IRB120, count, rng, lim)
    for k, (lo, hi) in zip(cal.learned.joints, cal.learned.training_ranges, strict=True):
        q[:, k] = np.clip(q[:, k], lo, hi)
    return q


def test_kept_term_is_in_the_files_and_evaluates_as_the_diagnosis_kernel(sag):
    res, folder, cal = sag
    rm = res.diagnosis.assessment.residual_model
    assert rm.kept and cal.learned is not None and res.learned_note is None
    doc = json.loads((folder / "compensation.json").read_text())
    entry = doc["learned_residual"]
    assert entry["withheld_rms_hybrid"] == rm.withheld_rms_hybrid
    assert entry["withheld_rms_physical"] == rm.withheld_rms_physical
    assert set(entry["training_ranges"]) == set(rm.inputs)
    assert len(entry["train"]) == rm.n_poses and "pickle" not in json.dumps(entry)
    assert "LEARNED RESIDUAL TERM" in (folder / "calibrated.toml").read_text()
    # the file's plain-NumPy evaluation against scikit-learn's kernel in the diagnosis
    ctx = res.diagnosis.context
    rows = np.flatnonzero(ctx.meas.point_index == 0)[:50]
    q = ctx.q[ctx.meas.pose_index[rows]]
    g = rm.kernel.predict(rm.scaling(ctx, rows)).reshape(len(rows), -1, 3)  # the arm's frame
    turn = np.stack([rm.frame @ rotation_about(np.asarray(IRB120.axes[0]), a) for a in q[:, 0]])
    want = np.einsum("pij,pmj->pmi", turn, g)
    got = cal.learned.evaluate(q)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)


def test_compensation_with_the_term_lands_closer_on_the_truth(sag):
    _, _, cal = sag
    physical = dataclasses.replace(cal, learned=None)
    q = _inside(cal, 80, seed=5)
    truth = synthesize(IRB120, q, SAG, rng=np.random.default_rng(0), noise_sigma=0.0)
    achieved = {}
    for name, c in (("hybrid", cal), ("physical", physical)):
        errs = []
        for j, lab in enumerate(c.tool_labels):
            target = truth.xyz[truth.point_index == j]
            # near-singular targets compensated too (flagged): random poses include some
            comp = compensate(c, target, q + 0.01, point=lab, frame="instrument",
                              accept_flagged=True)
            assert comp.converged.all() and not comp.outside_measured.any()
            hit = synthesize(IRB120, comp.q_command, SAG, rng=np.random.default_rng(0),
                             noise_sigma=0.0)
            errs.append(np.linalg.norm(hit.xyz[hit.point_index == j] - target, axis=1))
        achieved[name] = float(np.sqrt(np.mean(np.concatenate(errs) ** 2)))
    print(achieved)
    # the sag the physical model leaves is 0.033 mm RMS here; the term takes most of it
    assert achieved["hybrid"] < 0.6 * achieved["physical"], achieved


def test_targets_outside_the_training_ranges_are_refused_or_flagged(sag):
    _, _, cal = sag
    term = cal.learned
    k = term.joints[1]
    lo, hi = term.training_ranges[1]
    narrow = list(term.training_ranges)
    narrow[1] = (lo, lo + 0.3 * (hi - lo))  # the term as if trained on a third of joint k
    c = dataclasses.replace(cal, learned=dataclasses.replace(term, training_ranges=tuple(narrow)))
    q = _inside(cal, 6, seed=9)
    q[:, k] = lo + 0.8 * (hi - lo)
    target = cal.predict(q, point=cal.tool_labels[0])
    with pytest.raises(UnmeasuredTargetError, match="learned residual term was trained on"):
        compensate(c, target, q, point=cal.tool_labels[0], frame="instrument")
    comp = compensate(c, target, q, point=cal.tool_labels[0], frame="instrument",
                      accept_flagged=True)
    assert comp.outside_measured.all()


@pytest.mark.parametrize("edit, field", [
    (lambda e: e["training_ranges"].update({e["inputs"][0]: [1.0, -1.0]}), "training_ranges"),
    (lambda e: e.update(coef=e["coef"][:-1]), "coef"),
    (lambda e: e.update(gamma=-0.5), "gamma"),
    (lambda e: e.update(ard=[0.0] * len(e["ard"])), "ard"),
    (lambda e: e.update(turn_axis=[0.0, 0.0, 2.0]), "turn_axis"),
    (lambda e: e.update(frame=[[1, 0, 0], [0, 1, 0], [0, 0, -1]]), "frame"),
])
def test_a_learned_field_outside_its_domain_is_refused_on_read(sag, tmp_path, edit, field):
    _, folder, _ = sag
    doc = json.loads((folder / "compensation.json").read_text())
    (tmp_path / "calibrated.toml").write_text((folder / "calibrated.toml").read_text())
    edit(doc["learned_residual"])
    write_bound(tmp_path / "compensation.json", doc)
    with pytest.raises(FieldDomainError, match=f"learned_residual.*{field}"):
        read_calibration(tmp_path / "compensation.json")


def test_scatter_only_keeps_no_term_and_writes_none(tmp_path):
    res = _calibrate(_measure(Injection(), seed=12, poses=300, scatter=0.05))
    s = res.diagnosis.assessment.remainder.structure
    assert s is not None and not s.structured
    assert not res.diagnosis.assessment.residual_model.kept
    assert res.robot.learned is None
    res.write(tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    assert json.loads((tmp_path / "compensation.json").read_text())["learned_residual"] is None
    assert "LEARNED" not in (tmp_path / "calibrated.toml").read_text()


def test_full_pose_refit_leaves_a_kept_term_out_and_says_why():
    """The term was trained on the position-only final model's residual: a calibration that
    is the full-pose refit does not carry it, and the note says so."""
    from types import SimpleNamespace

    from zrp.calibration.recipe import _learned
    diag = SimpleNamespace(assessment=SimpleNamespace(residual_model=SimpleNamespace(kept=True)))
    term, note = _learned(diag, full=object())
    assert term is None and "full-pose refit" in note and "--no-orientation" in note
    diag.assessment.residual_model.kept = False
    assert _learned(diag, full=object()) == (None, None)
