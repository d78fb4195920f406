"""Well-posed identification (zrp.gap.fit.wellposed), physical domains as constraints
(zrp.gap.model.domains, zrp.gap.fit.constrained) and the honest fallback wording (issue 22)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import zrp
from tests.measured import BASE_ROTATION, REFLECTORS, full_pose_measurements
from zrp.gap import diagnose
from zrp.gap.analysis.fallback import FinalChoice
from zrp.gap.fit.uncertainty import simultaneous_z
from zrp.gap.fit.wellposed import solve
from zrp.gap.model.domains import domain_violations, parameter_domain
from zrp.gap.model.problem import Problem
from zrp.gap.report import diagnosis_document, report_markdown, verdict_text
from zrp.kinematics.identification import axis_tangents

TILT = (3, 0, 1.5e-3)           # joint 3's axis tilted 1.5 mrad towards its first tangent
OFFSETS = {2: 1e-3, 4: -8e-4}   # rad


def ur_like() -> zrp.Manipulator:
    """A UR5-type arm (mm): axes 2, 3, 4 parallel, the wrist offsets of the UR5."""
    pts = np.array([[0, 0, 0], [0, 0, 89.2], [425, 0, 89.2], [817, 0, 89.2],
                    [817, 109.3, 89.2], [817, 109.3, -5.55], [817, 191.8, -5.55]], float)
    bodies = np.diff(np.vstack([[0.0, 0.0, 0.0], pts]), axis=0)
    axes = np.array([[0, 0, 1], [0, 1, 0], [0, 1, 0], [0, 1, 0], [0, 0, -1], [0, 1, 0]], float)
    return zrp.Manipulator.from_arrays(axes, bodies, axial=[0, 1, 0], transverse=[1, 0, 0],
                                       name="ur-like", length_unit="mm")


def _diagnose(model, meas):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(model, meas, seed=0)


def _orientation_error(diag, fit, model) -> float:
    """RMS angle (rad) between the flange orientation a fit predicts and the true one, on
    the withheld poses (the truth built here, independently of the fitting code)."""
    axes = np.array(model.axes, dtype=float)
    j, t, a = TILT
    v = axes[j - 1] + a * axis_tangents(axes[j - 1])[t]
    axes[j - 1] = v / np.linalg.norm(v)
    shift = np.zeros(model.n)
    for k, val in OFFSETS.items():
        shift[k - 1] = val
    q = diag.context.q[diag.withheld_poses]
    true = BASE_ROTATION @ zrp.forward_kinematics(model.with_arrays(axes=axes),
                                                  q + shift).rotation
    prob = Problem(diag.context, fit.specs, diag.withheld_poses, fit.base_rotation)
    rb, _ = prob.base(fit.theta)
    pred = rb @ zrp.forward_kinematics(model, q).rotation if fit is diag.nominal_fit else (
        rb @ prob._chain(fit.theta).rprev[:, model.n])
    e = pred @ np.swapaxes(true, 1, 2)
    ang = np.arccos(np.clip((np.trace(e, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))
    return float(np.sqrt(np.mean(ang ** 2)))


@pytest.fixture(scope="module")
def ur_positions():
    """One reflector, positions only, joints within +-0.35 rad: a common tilt of the axes
    is (nearly) invisible."""
    m = ur_like()
    meas = full_pose_measurements(m, 120, 3, tilt=TILT, tools=[[0.0, 60.0, 40.0]],
                                  probe_rotation=np.eye(3), sigma_orientation=1e-4,
                                  joint_offset=OFFSETS, quat=False, span_rad=0.35)
    return m, _diagnose(m, meas)


def test_positions_only_holds_the_unpinned_directions_and_names_them(ur_positions):
    _m, d = ur_positions
    held = d.held_directions
    assert held, "the common tilt of the axes is not pinned by one reflector's positions"
    h = held[0]
    assert h.singular_value <= h.threshold
    assert sum(n.startswith("u") and n.endswith(".t2") for n in h.parameters) >= 3
    doc = diagnosis_document(d)
    assert doc["identification"]["held_directions"][0]["parameters"] == list(h.parameters)
    assert doc["identification"]["solver"]["converged"] is True
    assert "stayed at their nominal values" in verdict_text(d)


def test_positions_only_names_the_held_tilt_by_the_distal_axis(ur_positions):
    """The held direction is a common tilt of axes 1-5 in the fit's parameters (which carry
    no tilt of axis 6); the name a reader sees says which axis turns against which, then the
    solver's loadings, unchanged."""
    _m, d = ur_positions
    h = d.held_directions[0]
    assert {f"u{k}.t2" for k in range(1, 6)} <= set(h.parameters)
    assert not any(n.startswith("u6.") for n in h.parameters)
    assert h.reading.startswith("axis 6 tilted against axes 1-5")
    assert h.label == f"{h.reading}: {h.combination}"
    assert h.label in verdict_text(d)
    assert diagnosis_document(d)["identification"]["held_directions"][0]["reading"] == h.reading
    assert f"| {h.label} |" in report_markdown(d)


def test_positions_only_orientation_no_worse_than_nominal(ur_positions):
    m, d = ur_positions
    nominal = _orientation_error(d, d.nominal_fit, m)
    final = _orientation_error(d, d.final_fit, m)
    assert final <= nominal, (final, nominal)


def test_full_pose_recovers_the_parameters_within_their_intervals():
    m = ur_like()
    meas = full_pose_measurements(m, 150, 5, tilt=TILT, tools=REFLECTORS,
                                  probe_rotation=np.eye(3), sigma_orientation=1e-4,
                                  joint_offset=OFFSETS)
    d = _diagnose(m, meas)
    truth = {"u3.t1": TILT[2], "q2.offset": OFFSETS[2], "q4.offset": OFFSETS[4]}
    fp = d.full_pose.fit  # positions and orientations together
    nreg = len(d.registration)
    names = [sp.name for sp in fp.specs[nreg:]]
    assert set(truth) <= set(names), names
    z = simultaneous_z(len(names))  # every effect parameter at once (Sidak)
    for i, name in enumerate(names, nreg):
        err = abs(fp.theta[i] - truth.get(name, 0.0))
        assert err <= z * fp.stderr[i], (name, fp.theta[i], fp.stderr[i])
    assert not d.held_directions and d.final_fit.converged and not d.solver_stops
    assert d.full_pose.fit.converged
    fp_doc = diagnosis_document(d)["identification"]["full_pose"]
    assert fp_doc["converged"] is True and fp_doc["outside_domain"] == []
    # withheld orientation error beside the position error: nominal, final, geometric
    ori_nominal = d.full_pose.withheld_orientation_nominal
    noise = np.sqrt(3.0) * 1e-4  # RMS angle of the orientation noise
    assert d.full_pose.withheld_orientation_after <= 1.2 * noise
    assert d.full_pose.withheld_orientation_before <= 1.2 * noise < ori_nominal
    assert d.full_pose.baseline_withheld is not None
    assert f"{1e3 * ori_nominal:.3g} mrad after registration" in verdict_text(d)


def test_solver_is_the_map_estimate_of_a_linear_problem():
    """On a linear residual r = A theta - y the solver's answer is the closed form of eq. W4:
    ordinary least squares on the directions above the noise, shrunk by s^2/(s^2+sigma^2),
    the rest at the prior; computed here from numpy's SVD of the scaled matrix."""
    rng = np.random.default_rng(4)
    A = rng.normal(size=(300, 5))
    A[:, 4] = A[:, 3] + 1e-4 * rng.normal(size=300)   # a nearly aliased pair
    truth = np.array([1.0, -2.0, 0.5, 0.3, 0.0])
    y = A @ truth + 0.05 * rng.normal(size=300)
    scales = np.array([10.0, 10.0, 10.0, 1.0, 1.0])
    sol = solve(lambda th: (A @ th - y, A), lambda th: A @ th - y, np.zeros(5), np.zeros(5),
                scales, [f"p{i}" for i in range(5)])
    U, s, Vt = np.linalg.svd(A * scales, full_matrices=False)
    sigma = np.linalg.norm(A @ np.linalg.lstsq(A, y, rcond=None)[0] - y) / np.sqrt(300 - 5)
    keep = s > sigma
    f = np.where(keep, s / (s * s + sigma * sigma), 0.0)
    x = Vt.T @ (f * (U.T @ y))
    np.testing.assert_allclose(sol.theta, scales * x, rtol=1e-8, atol=1e-10)
    assert sol.converged and len(sol.held) == 1
    assert set(sol.held[0].parameters) == {"p3", "p4"}


def test_domains_table():
    assert parameter_domain("q2.backlash", "backlash", "rad").lo == 0.0
    assert parameter_domain("q2.compliance", "joint_compliance", "rad/(N m)").lo == 0.0
    # a lumped-mass weight alone has no domain (the joint's sum has: >= 0)
    assert parameter_domain("q2.w_p3", "joint_compliance", "rad/mm") is None
    assert parameter_domain("base.rx", "base_frame", "rad") is None
    assert parameter_domain("u2.t1", "axis_misalignment", "rad", max_tilt_rad=0.1).hi == 0.1
    b_mm = parameter_domain("b3.x", "link_length", "mm")
    b_m = parameter_domain("b3.x", "link_length", "m")
    assert b_mm.hi == pytest.approx(1e3 * b_m.hi)
    bad = domain_violations(["q1.backlash", "q2.sin1", "q2.cos1", "u1.t1"],
                            ["backlash", "cyclic_error", "cyclic_error", "axis_misalignment"],
                            ["rad"] * 4, [-1e-4, 4e-3, 4e-3, 1e-3])
    assert [i for i, _ in bad] == [0, 1, 2]  # negative play; amplitude 5.7 mrad > 5 mrad


def test_a_five_fold_worse_model_is_not_within_the_noise():
    ch = FinalChoice("geometric_baseline", 2.204, 0.418, z=1.0)
    assert not ch.within_noise
    assert "5.27x worse" in ch.note("mm") and "equally good" not in ch.note("mm")
    assert FinalChoice("geometric_baseline", 0.101, 0.100, z=1.0).within_noise
    assert FinalChoice("search", 0.5, 0.6).note("mm") == ""


def test_a_solver_stopped_early_says_so_in_the_result_and_the_verdict(ur_positions):
    """A Gauss-Newton solve cut at one iteration on a nonlinear problem reports it (field and
    words); a diagnosis with such a fit names it in its verdict and diagnosis.json."""
    _m, d = ur_positions
    f = d.final_fit
    prob = Problem(d.context, f.specs, d.fitting_poses, f.base_rotation)
    start = np.array(f.theta)
    start[-1] += 5e-3  # away from the solution: one step does not get there
    sol = solve(prob.residual_and_jacobian, prob.residual, start, start * 0, np.ones(len(start)),
                [s.name for s in f.specs], max_iterations=1)
    assert not sol.converged and "iteration limit (1)" in sol.reason
    msg = f"least squares with {len(f.specs)} parameters: {sol.reason}"
    stopped = dataclasses.replace(d, warnings=(msg,))
    assert stopped.solver_stops == (msg,)
    assert "stopped before converging" in verdict_text(stopped)
    assert diagnosis_document(stopped)["identification"]["stopped_early"] == [msg]
    assert not d.solver_stops and "stopped before" not in verdict_text(d)


def test_a_tilt_beyond_the_default_domain_needs_the_widen_option():
    """A 12 mrad axis tilt is outside the default domain (a few mrad of a machined part): not
    used; with max_tilt_rad widened it is identified within its interval."""
    from zrp.gap import Injection, synthesize
    from zrp.kinematics import uniform_joint_values

    puma = zrp.load_model("puma")
    rng = np.random.default_rng(2)
    q = uniform_joint_values(puma, 150, rng)
    meas = synthesize(puma, q, Injection(tilt={3: (12e-3, 0.0)}), rng=rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        narrow = diagnose(puma, meas, seed=0)
        wide = diagnose(puma, meas, seed=0, max_tilt_rad=0.02)
    assert all(abs(v) <= 5e-3 for s, v in zip(narrow.final_fit.specs, narrow.final_fit.theta,
                                              strict=True) if s.effect == "axis_misalignment")
    assert any("u3.t1" in n for _, n in narrow.outside_domain)
    p = wide.parameter("u3.t1")
    assert p.ci95_effect[0] <= 12e-3 <= p.ci95_effect[1]
    assert wide.final.rms < narrow.final.rms
    with pytest.raises(zrp.errors.InputError, match="max_tilt_rad"):
        diagnose(puma, meas, max_tilt_rad=-1.0)
