"""Eqs (15)-(17) along a joint trajectory: closed forms for link and axis errors."""

from __future__ import annotations

import numpy as np
import pytest

from zrp import load_model
from zrp.errors import InputError
from zrp.manufacturing.deviation import pose_deviation, trajectory_deviation
from zrp.manufacturing.perturb import Perturbation


def _joint_path(n: int, steps: int = 200, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A smooth joint trajectory covering large joint angles (independent of the IK)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0, steps)
    amp = rng.uniform(0.5, 2.5, n)
    phase = rng.uniform(0, 2 * np.pi, n)
    return t, amp * np.sin(np.pi * t[:, None] + phase)


@pytest.mark.parametrize("name,k", [("LE2", 2), ("LE3", 3), ("LE4", 4), ("LE7", 7)])
@pytest.mark.parametrize("xi", [0.02, -0.07, 0.1])
def test_link_error_is_xi_times_length_everywhere(name, k, xi):
    model = load_model("puma")
    t, q = _joint_path(6)
    dev = trajectory_deviation(model, Perturbation.single(name, xi), q, t)
    expected = abs(xi) / 100 * np.linalg.norm(model.bodies[k - 1])
    np.testing.assert_allclose(dev.delta_p, expected, rtol=1e-9)
    # link errors leave the orientation unchanged (exactly, up to rounding)
    assert dev.max_angle_rad < 1e-15 and dev.max_delta_r < 1e-15


def test_zero_perturbation_is_zero():
    model = load_model("puma")
    t, q = _joint_path(6)
    dev = trajectory_deviation(model, Perturbation({"LE2": 0.0, "JE3": 0.0}), q, t)
    assert dev.max_delta_p == 0.0 and dev.max_angle_rad == 0.0


def test_axis_error_rotation_closed_form():
    """A tilt alpha of axis k turned by q_k gives an error rotation with scalar part
    cos(q/2)^2 + sin(q/2)^2 cos(alpha), i.e. theta = 4 asin(|sin(q_k/2)| sin(alpha/2)); eq (15)
    gives 2 sqrt(2) sin(theta/2)."""
    model = load_model("puma")
    t, q = _joint_path(6, seed=3)
    for k in range(1, 7):
        xi = 0.1
        dev = trajectory_deviation(model, Perturbation.single(f"JE{k}", xi), q, t)
        alpha = np.arctan(np.sqrt(2) * 1e-3 / (1 + 1e-3))
        theta = 4 * np.arcsin(np.abs(np.sin(q[:, k - 1] / 2)) * np.sin(alpha / 2))
        np.testing.assert_allclose(dev.angle_rad, theta, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(dev.delta_r, 2 * np.sqrt(2) * np.sin(theta / 2), rtol=1e-9,
                                   atol=1e-15)


def test_literal_eq15_has_a_rounding_floor():
    """The literal eq (15) cannot resolve an exactly-zero error (cf. the paper's 5.96E-8 =
    2^-24 at 0 %); the rounding-free form used for delta_R returns 0."""
    from zrp import end_effector_pose
    from zrp.manufacturing.deviation import delta_r_eq15, delta_r_literal
    from zrp.rotations.rodrigues import er_conjugate, er_multiply

    model = load_model("puma")
    _, q = _joint_path(6)
    _, e = end_effector_pose(model, q)
    err = er_multiply(e, er_conjugate(e))  # the identity, composed in double precision
    lit = delta_r_literal(err)
    assert lit.max() > 1e-9 and lit.max() < 2e-7
    assert delta_r_eq15(err).max() < 1e-14


def test_sign_zero_zero_kills_axis_errors():
    model = load_model("puma")
    t, q = _joint_path(6)
    for k in range(1, 7):
        dev = trajectory_deviation(model, Perturbation.single(f"JE{k}", 0.1, sign_zero_axes=0),
                                   q, t)
        assert dev.max_delta_p < 1e-12 and dev.max_angle_rad < 1e-15


def test_linear_in_small_xi():
    model = load_model("puma")
    t, q = _joint_path(6, seed=5)
    for name in ("JE2", "JE5", "LE3"):
        d1 = trajectory_deviation(model, Perturbation.single(name, 0.01), q, t)
        d2 = trajectory_deviation(model, Perturbation.single(name, 0.02), q, t)
        assert d2.max_delta_p == pytest.approx(2 * d1.max_delta_p, rel=2e-4)
        if name.startswith("JE"):
            assert d2.max_delta_r == pytest.approx(2 * d1.max_delta_r, rel=2e-4)


def test_bad_input():
    model = load_model("puma")
    t, q = _joint_path(6)
    with pytest.raises(InputError, match="t: expected shape"):
        trajectory_deviation(model, Perturbation(), q, t[:-1])
    with pytest.raises(InputError, match="q"):
        trajectory_deviation(model, Perturbation(), q[:, :5], t)
    with pytest.raises(InputError, match="perturbation"):
        trajectory_deviation(model, {"LE2": 0.1}, q, t)
    with pytest.raises(InputError, match="joints"):
        pose_deviation(model, load_model("scara"), q, t)
