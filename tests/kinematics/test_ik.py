"""Trajectory inverse kinematics: accuracy, integrator order, singularities, errors."""

import numpy as np
import pytest

import zrp
from zrp.rotations.rodrigues import er_angle, er_conjugate, er_multiply
from zrp.testing import random_arm


@pytest.fixture(scope="module")
def circle_ik():
    return zrp.puma_circle_ik(steps=1000)


def test_paper_circle_tracked_beyond_paper_accuracy(circle_ik):
    setup = zrp.puma_circle()
    # independent check: the vectorised NumPy FK of the joint trajectory against the circle
    fk = zrp.forward_kinematics(setup.model, circle_ik.q)
    want = setup.trajectory.evaluate(circle_ik.t)
    er0 = zrp.forward_kinematics(setup.model, setup.q0).er
    # mm (the paper's own 0 % row is 1.07e-8 mm) and rad: the hand keeps its start orientation
    zrp.testing.assert_pose_close(fk, (want.position, np.broadcast_to(er0, fk.er.shape)),
                                  atol_position=1e-9, atol_rotation_rad=1e-10)
    assert circle_ik.position_error.max() <= 1e-9
    # the circle really is a 125 mm circle in the plane x = 558.8 mm
    np.testing.assert_allclose(np.linalg.norm(fk.position - setup.trajectory.center, axis=1),
                               125.0, atol=1e-9)
    np.testing.assert_allclose(fk.position[:, 0], 558.8, atol=1e-9)
    # and it closes: ends where it started, at rest
    np.testing.assert_allclose(circle_ik.q[-1], circle_ik.q[0], atol=1e-9)
    np.testing.assert_allclose(circle_ik.qdot[[0, -1]], 0.0, atol=1e-9)


def test_paper_circle_reports_per_step_diagnostics(circle_ik):
    s = circle_ik.summary()
    assert s["steps"] == 1000
    assert s["damped_steps"] == 0
    assert s["min_manipulability"] > 0.03
    # the correction removes what the integrator leaves: nonzero, but small per step
    assert 0 < circle_ik.correction.max() < 1e-7
    assert 0 < circle_ik.drift_position.max() < 1e-6
    assert circle_ik.manipulability.shape == circle_ik.t.shape


def test_predictor_corrector_is_fourth_order():
    setup = zrp.puma_circle()
    errs = []
    for steps in (100, 200, 400):
        r = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, steps,
                                 correction="none")
        errs.append(r.position_error.max())
    ratios = [errs[0] / errs[1], errs[1] / errs[2]]
    # order 4 -> ratio 16 per halving; accept 10..25 (pre-asymptotic and start effects)
    assert all(10 < r < 25 for r in ratios), (errs, ratios)


def test_feedback_correction_bounds_drift():
    setup = zrp.puma_circle()
    none = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000,
                                correction="none")
    fb = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000,
                              correction="feedback", gain=50.0)
    assert fb.position_error.max() < 0.5 * none.position_error.max()
    with pytest.warns(zrp.TrackingWarning, match="stability region"):
        zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 200,
                             correction="feedback", gain=50.0)


def test_line_and_user_function_trajectories(puma):
    q0 = np.radians([10, -20, 30, 0, 60, 0])
    p0 = zrp.forward_kinematics(puma, q0).position
    line = zrp.Line(p0, p0 + np.array([50.0, -80.0, 40.0]), duration=2.0)
    r = zrp.track_trajectory(puma, line, q0, 300)
    fk = zrp.forward_kinematics(puma, r.q).position
    np.testing.assert_allclose(fk, line.evaluate(r.t).position, atol=1e-9)

    def spiral(t):
        return p0 + np.column_stack([20 * np.sin(t), 30 * (1 - np.cos(t)), 10 * t])

    traj = zrp.FunctionTrajectory(spiral, duration=2.0)
    r = zrp.track_trajectory(puma, traj, q0, 300)
    np.testing.assert_allclose(zrp.forward_kinematics(puma, r.q).position, spiral(r.t),
                               atol=1e-9)


def test_prescribed_orientation_law(puma):
    q0 = np.radians([0, 0, 0, 0, 90, 0])
    setup = zrp.puma_circle()
    er0 = zrp.forward_kinematics(puma, q0).er
    axis = np.array([1.0, 0.0, 0.0])
    rate = 0.2  # rad/s about the tool axis (+x in the base frame)

    def law(t):
        twist = zrp.rotations.rodrigues.er_from_axis_angle(axis, rate * t)
        return er_multiply(twist, er0), np.tile(axis * rate, (t.size, 1))

    traj = zrp.Circle(setup.trajectory.center, setup.trajectory.normal,
                      setup.trajectory.start_point, duration=4.0, orientation=law)
    r = zrp.track_trajectory(puma, traj, q0, 500)
    fk = zrp.forward_kinematics(puma, r.q)
    want, _ = law(r.t)
    assert er_angle(er_multiply(fk.er, er_conjugate(want))).max() < 1e-10


def test_position_task_for_four_joint_scara():
    scara = zrp.load_model("scara")
    q0 = np.array([0.3, 1.2, 50.0, 0.0])
    p0 = zrp.forward_kinematics(scara, q0).position
    c = zrp.Circle.from_start(p0, 60.0, [0, 0, 1], -p0 * [1, 1, 0], duration=3.0)
    r = zrp.track_trajectory(scara, c, q0, 400)
    assert r.task == "position"
    assert r.position_error.max() < 1e-9
    # prismatic columns are scaled like revolute ones: a healthy SCARA is not "near a
    # singularity" (it was, on every sample, when the quill's column was left in mm per mm)
    assert r.damping.max() == 0.0
    assert r.manipulability.min() > 0.01


def _well_conditioned_arm(rng, n, pp):
    """A random arm and start configuration away from singularities (smallest singular value
    of the scaled Jacobian above 0.2)."""
    while True:
        model = random_arm(rng, n, pp)
        q0 = rng.uniform(-1, 1, n)
        jac = zrp.jacobian(model, q0)
        jac[3:] /= model.characteristic_length
        if np.linalg.svd(jac, compute_uv=False)[-1] > 0.05:
            return model, q0


def test_redundant_and_prismatic_arms(rng):
    for n, pp in ((7, 0.0), (7, 0.4), (6, 0.3)):
        model, q0 = _well_conditioned_arm(rng, n, pp)
        p0 = zrp.forward_kinematics(model, q0).position
        c = zrp.Circle.from_start(p0, 20.0, rng.normal(size=3), rng.normal(size=3), duration=2.0)
        r = zrp.track_trajectory(model, c, q0, 400)
        assert r.position_error.max() < 1e-9, model
        assert r.orientation_error.max() < 1e-10, model


def test_start_at_wrist_singularity_warns_with_time_and_point(puma):
    q0 = np.zeros(6)  # Table 1's zero reference: u4 = -u6
    p0 = zrp.forward_kinematics(puma, q0).position
    c = zrp.Circle.from_start(p0, 125.0, [0, 0, 1], [0, 1, 0], duration=4.0)
    with pytest.warns(zrp.SingularityWarning, match=r"t = .* point \["):
        r = zrp.track_trajectory(puma, c, q0, 400)
    assert r.damping.max() > 0
    assert np.all(np.isfinite(r.q))


def test_unreachable_circle_is_an_error_with_time_and_point(puma):
    q0 = np.radians([0, 0, 0, 0, 90, 0])
    p0 = zrp.forward_kinematics(puma, q0).position
    c = zrp.Circle.from_start(p0, 900.0, [1, 0, 0], [0, 0, 1], duration=4.0)
    with pytest.raises(zrp.UnreachableError, match=r"t = [\d.]+ s: point \["):
        zrp.track_trajectory(puma, c, q0, 200)


def test_bad_ik_inputs(puma):
    setup = zrp.puma_circle()
    tr, q0 = setup.trajectory, setup.q0
    with pytest.raises(zrp.InputError, match="steps: expected an integer >= 4"):
        zrp.track_trajectory(puma, tr, q0, 2)
    with pytest.raises(zrp.InputError, match=r"task: 'orientation' is unknown.*'pose'"):
        zrp.track_trajectory(puma, tr, q0, task="orientation")  # type: ignore[arg-type]
    with pytest.raises(zrp.InputError, match=r"correction: 'magic'.*newton"):
        zrp.track_trajectory(puma, tr, q0, correction="magic")  # type: ignore[arg-type]
    with pytest.raises(zrp.InputError, match=r"q0: joint 2 \(q2\) is nan"):
        zrp.track_trajectory(puma, tr, [0, np.nan, 0, 0, 0, 0])
    with pytest.raises(zrp.InputError, match="trajectory: expected a zrp Trajectory"):
        zrp.track_trajectory(puma, lambda t: t, q0)  # type: ignore[arg-type]
    with pytest.raises(zrp.InputError, match="gain"):
        zrp.track_trajectory(puma, tr, q0, gain=-1.0)


@pytest.mark.parametrize("name", ["position_tol", "orientation_tol_rad"])
@pytest.mark.parametrize("value", [0.0, -1e-9, float("nan"), float("inf"), "1e-9"])
def test_a_tolerance_that_is_not_positive_and_finite_is_refused_by_name(puma, name, value):
    """Issue 35, finding 11: a zero, negative or NaN Newton tolerance was taken silently."""
    setup = zrp.puma_circle()
    with pytest.raises(zrp.InputError, match=rf"^{name}: expected a (finite )?number"):
        zrp.track_trajectory(puma, setup.trajectory, setup.q0, 8, **{name: value})


def test_max_iter_below_one_is_refused(puma):
    setup = zrp.puma_circle()
    with pytest.raises(zrp.InputError, match="max_iter: expected a whole number >= 1"):
        zrp.track_trajectory(puma, setup.trajectory, setup.q0, 8, max_iter=0)


def test_bad_trajectory_inputs():
    with pytest.raises(zrp.InputError, match="normal: is a zero vector"):
        zrp.Circle([0, 0, 0], [0, 0, 0], [1, 0, 0])
    with pytest.raises(zrp.InputError, match="out of the circle's plane"):
        zrp.Circle([0, 0, 0], [0, 0, 1], [1, 0, 1])
    with pytest.raises(zrp.InputError, match="radius: 2 disagrees"):
        zrp.Circle([0, 0, 0], [0, 0, 1], [1, 0, 0], radius=2.0)
    with pytest.raises(zrp.InputError, match="duration: expected a positive"):
        zrp.Line([0, 0, 0], [1, 0, 0], duration=0.0)
    with pytest.raises(zrp.InputError, match=r"time_law: 'linear' is unknown.*quintic"):
        zrp.Line([0, 0, 0], [1, 0, 0], time_law="linear")
    with pytest.raises(zrp.InputError, match=r"t: times must lie in \[0, 2\]"):
        zrp.Line([0, 0, 0], [1, 0, 0], duration=2.0).evaluate([0.0, 3.0])
    bad = zrp.FunctionTrajectory(lambda t: np.zeros((t.size, 2)), duration=1.0)
    with pytest.raises(zrp.InputError, match=r"position: expected shape"):
        bad.evaluate([0.5])
    nan = zrp.FunctionTrajectory(lambda t: np.full((t.size, 3), np.nan), duration=1.0)
    with pytest.raises(zrp.InputError, match="non-finite value at t"):
        nan.evaluate([0.5])


def test_time_laws_start_and_end_at_rest():
    for kind in ("quintic", "cycloidal"):
        s, ds, dds = zrp.TimeLaw(kind)(np.array([0.0, 1.0]))
        np.testing.assert_allclose(s, [0, 1], atol=1e-15)
        np.testing.assert_allclose(ds, 0, atol=1e-15)
        np.testing.assert_allclose(dds, 0, atol=1e-12)
        # derivatives match finite differences
        tau = np.linspace(0.1, 0.9, 9)
        h = 1e-6
        sp, _, _ = zrp.TimeLaw(kind)(tau + h)
        sm, _, _ = zrp.TimeLaw(kind)(tau - h)
        _, d1, _ = zrp.TimeLaw(kind)(tau)
        np.testing.assert_allclose(d1, (sp - sm) / (2 * h), atol=1e-8)


def test_circle_velocity_and_acceleration_match_finite_differences():
    c = zrp.puma_circle().trajectory
    t = np.linspace(0.2, 3.8, 7)
    h = 1e-5
    s, sp, sm = c.evaluate(t), c.evaluate(t + h), c.evaluate(t - h)
    np.testing.assert_allclose(s.velocity, (sp.position - sm.position) / (2 * h), atol=1e-5)
    np.testing.assert_allclose(s.acceleration, (sp.velocity - sm.velocity) / (2 * h), atol=1e-4)


def test_save_csv_refuses_overwrite(tmp_path, circle_ik):
    path = circle_ik.save_csv(tmp_path / "q.csv")
    with pytest.raises(zrp.OutputExistsError):
        circle_ik.save_csv(path)
    data = np.genfromtxt(path, delimiter=",", names=True)
    np.testing.assert_allclose(data["q5"], circle_ik.q[:, 4], rtol=0, atol=0)
