"""Orientation as data (issue 22): measured orientations enter the search's fits and the
geometric baseline, not only a refit afterwards, and pin a direction positions cannot.

The truth: a UR-type arm (tests/gap/test_wellposed.py) whose parallel axes 2, 3 and 4 are all
tilted by the same 2 mrad towards their second tangent (a common tilt), measured with one
reflector in a small joint range. Positions alone hold this common tilt at its nominal value
(it is nearly a gauge direction with the base rotation); the same poses with the flange
orientation measured identify it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import zrp
from tests.gap.test_wellposed import ur_like
from tests.measured import BASE_ROTATION, BASE_TRANSLATION
from zrp.gap import Measurements, diagnose
from zrp.gap.fit.uncertainty import simultaneous_z
from zrp.gap.model.domains import tolerance
from zrp.gap.report import diagnosis_document, report_markdown
from zrp.kinematics import uniform_joint_values
from zrp.kinematics.identification import axis_tangents

COMMON = (2, 3, 4)      # the parallel axes, tilted together
ANGLE = 2e-3            # rad, towards tangent 1 (the "t2" parameters)
SIGMA_O = 1e-4          # rad per component


def _measurements(model: zrp.Manipulator, quat: bool) -> Measurements:
    """120 poses in +-0.35 rad, one reflector, 0.02 mm position noise; with ``quat`` the
    flange orientation too (the same positions either way)."""
    rng = np.random.default_rng(3)
    n = 120
    q = uniform_joint_values(model, n, rng, np.tile([-0.35, 0.35], (model.n, 1)))
    axes = np.array(model.axes, dtype=float)
    for j in COMMON:
        v = axes[j - 1] + ANGLE * axis_tangents(axes[j - 1])[1]
        axes[j - 1] = v / np.linalg.norm(v)
    fk = zrp.forward_kinematics(model.with_arrays(axes=axes), q)
    y = fk.position + fk.rotation @ np.array([0.0, 60.0, 40.0])
    xyz = y @ BASE_ROTATION.T + BASE_TRANSLATION + rng.normal(scale=0.02, size=y.shape)
    noise = Rotation.from_rotvec(rng.normal(scale=SIGMA_O, size=(n, 3))).as_matrix()
    wxyz = Rotation.from_matrix(noise @ BASE_ROTATION @ fk.rotation).as_quat()[:, [3, 0, 1, 2]]
    return Measurements.from_arrays(np.arange(n), q, xyz, quat=wxyz if quat else None)


def _run(quat: bool):
    m = ur_like()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(m, _measurements(m, quat), seed=0)


@pytest.fixture(scope="module")
def both():
    return _run(False), _run(True)


def _common(fit) -> dict[str, tuple[float, float]]:
    return {s.name: (float(fit.theta[i]), float(fit.stderr[i]))
            for i, s in enumerate(fit.specs) if s.name in {f"u{j}.t2" for j in COMMON}}


def _tol(name: str) -> float:
    effect, unit = {"u": ("axis_misalignment", "rad"), "b": ("link_length", "mm")}.get(
        name[0], ("joint_offset", "rad"))
    return tolerance(name, effect, unit)


def _along(h, fit) -> float:
    """The held combination v^T x of a fit (x: the values in tolerance units, eq. W2; a
    parameter the fit does not carry is at its nominal 0)."""
    val = {s.name: float(fit.theta[i]) for i, s in enumerate(fit.specs)}
    return sum(w * val.get(n, 0.0) / _tol(n)
               for n, w in zip(h.parameters, h.weights, strict=True))


def _truth_along(h) -> float:
    return sum(w * ANGLE / _tol(n) for n, w in zip(h.parameters, h.weights, strict=True)
               if n in {f"u{j}.t2" for j in COMMON})


def test_positions_alone_hold_the_common_tilt(both):
    pos, six = both
    assert pos.context.orientation is None and pos.full_pose is None
    held = [h for h in pos.held_directions
            if {f"u{j}.t2" for j in COMMON} <= set(h.parameters)]
    assert len(held) == 1, [h.combination for h in pos.held_directions]
    h = held[0]
    # positions alone: the combination stays at its nominal 0, far from the truth's;
    # with orientations it is estimated at the truth's
    for fit in (pos.assessment.choice.search_fit, pos.assessment.baseline.fit):
        truth = _truth_along(h)
        assert abs(_along(h, fit)) < 0.1 * abs(truth), (_along(h, fit), truth)
    for fit in (six.assessment.choice.search_fit, six.assessment.baseline.fit):
        truth = _truth_along(h)
        assert abs(_along(h, fit) - truth) < 0.1 * abs(truth), (_along(h, fit), truth)


def test_orientations_identify_it_in_the_search_and_the_baseline(both):
    _, six = both
    assert six.context.orientation is not None
    assert not six.held_directions
    # the search's own model (before the choice of the final one) and the geometric
    # baseline: each of the three tilts at the truth within its simultaneous interval
    for fit in (six.assessment.choice.search_fit, six.assessment.baseline.fit):
        assert fit.probe_rotation is not None  # fitted with the orientations
        vals = _common(fit)
        assert len(vals) == len(COMMON), vals
        z = simultaneous_z(len(vals))
        for name, (v, se) in vals.items():
            assert abs(v - ANGLE) <= z * se, (name, v, se)
            assert se < 0.25 * ANGLE, (name, se)
    assert "axis_misalignment" in [s.effect for s in six.steps]


def test_withheld_orientation_error_of_the_final_model_is_reported(both):
    pos, six = both
    fp = six.full_pose
    noise = np.sqrt(3.0) * SIGMA_O  # RMS angle of the orientation noise
    assert fp.withheld_orientation_final <= 1.3 * noise < fp.withheld_orientation_nominal
    doc = diagnosis_document(six)
    weights = doc["settings"]["orientation_weights"]
    assert weights["sigma_orientation_rad"] == pytest.approx(SIGMA_O, rel=0.25)
    assert weights["sigma_position"] == pytest.approx(0.02, rel=0.25)
    assert weights["source"] == "estimated" and "orientation_weights" not in diagnosis_document(
        pos)["settings"]
    assert doc["full_pose"]["withheld_orientation_rms_final_model_rad"] == pytest.approx(
        fp.withheld_orientation_final)
    assert f"{1e3 * fp.withheld_orientation_final:.3g} mrad withheld orientation" in doc[
        "verdict"]
    assert "withheld orientation error" in report_markdown(six)
    # the same positions without orientations: worse in position on withheld poses too
    # (the held tilt stays unmodelled), never better
    assert six.final.rms <= pos.final.rms
