"""The identification Jacobian against central finite differences of the exact kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from zrp import end_effector_pose, jacobian, load_model
from zrp.errors import InputError
from zrp.kinematics.identification import (
    apply_parameters,
    axis_tangents,
    parameter_jacobian,
    parameter_names,
    parameter_space,
    perturbed_arrays,
)
from zrp.model.manipulator import Manipulator
from zrp.rotations.rodrigues import er_conjugate, er_multiply, rotvec_from_er


def _pose_error(model, model_a, q, off=None):
    """[rotvec(E_a conj(E_d)); p_a - p_d] of the same joints, shape (..., 6)."""
    p_d, e_d = end_effector_pose(model, q)
    qa = q if off is None else q + off
    p_a, e_a = end_effector_pose(model_a, qa)
    rv = rotvec_from_er(er_multiply(e_a, er_conjugate(e_d)))
    return np.concatenate([rv, p_a - p_d], axis=-1)


def _fd_jacobian(model, q, joint_offsets, h_len=1e-4, h_ang=1e-6):
    space = parameter_space(model, joint_offsets=joint_offsets)
    cols = []
    for i in range(space.size):
        h = h_ang if space.units[i] == "rad" else h_len
        dx = np.zeros(space.size)
        dx[i] = h
        mp, offp = apply_parameters(model, dx, joint_offsets=joint_offsets)
        mm, offm = apply_parameters(model, -dx, joint_offsets=joint_offsets)
        ep = _pose_error(model, mp, q, offp)
        em = _pose_error(model, mm, q, offm)
        cols.append((ep - em) / (2 * h))
    return np.stack(cols, axis=-1)


def _random_arm(rng: np.random.Generator, n: int, prismatic: bool) -> Manipulator:
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    bodies = rng.uniform(-300, 300, size=(n + 1, 3))
    types = ["revolute"] * n
    if prismatic:
        types[n // 2] = "prismatic"
    return Manipulator.from_arrays(axes, bodies, axial=[0, 0, 1], transverse=[1, 0, 0],
                                   types=types, name="random")


@pytest.mark.parametrize("name", ["puma", "stanford", "scara"])
def test_matches_finite_differences_builtin(name):
    model = load_model(name)
    rng = np.random.default_rng(11)
    q = rng.uniform(-2.5, 2.5, size=(3, model.n))
    jac = parameter_jacobian(model, q, joint_offsets=True)
    fd = _fd_jacobian(model, q, True)
    scale = np.abs(fd).max()
    np.testing.assert_allclose(jac, fd, atol=1e-6 * scale)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_matches_finite_differences_random_arm(seed):
    rng = np.random.default_rng(seed)
    model = _random_arm(rng, 5, prismatic=seed == 2)
    q = rng.uniform(-3, 3, size=(2, model.n))
    if seed == 2:
        q[:, model.n // 2] = rng.uniform(50, 200, size=2)
    jac = parameter_jacobian(model, q, joint_offsets=True)
    fd = _fd_jacobian(model, q, True)
    np.testing.assert_allclose(jac, fd, atol=1e-6 * np.abs(fd).max())


def test_offsets_are_the_eq7_jacobian_and_bodies_leave_orientation():
    model = load_model("puma")
    q = np.random.default_rng(0).uniform(-3, 3, size=(4, 6))
    jac = parameter_jacobian(model, q, joint_offsets=True)
    np.testing.assert_allclose(jac[..., -6:], jacobian(model, q), atol=1e-12)
    nb = 3 * (model.n + 1)
    assert np.all(jac[..., 0:3, :nb] == 0.0)  # link errors never rotate the hand
    # d p / d b_{k,0} is a rotation matrix
    for k in range(model.n + 1):
        block = jac[..., 3:6, 3 * k:3 * k + 3]
        np.testing.assert_allclose(block @ np.swapaxes(block, -1, -2),
                                   np.broadcast_to(np.eye(3), block.shape), atol=1e-12)


def test_names_and_shapes():
    model = load_model("puma")
    names = parameter_names(model)
    assert len(names) == 33 and names[:3] == ("b1.x", "b1.y", "b1.z")
    assert names[21] == "u1.t1" and names[-1] == "u6.t2"
    assert parameter_jacobian(model, np.zeros(6)).shape == (6, 33)
    assert parameter_jacobian(model, np.zeros((2, 5, 6)), joint_offsets=True).shape == (2, 5, 6, 39)


def test_tangents_orthonormal():
    u = np.random.default_rng(4).normal(size=(50, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    t = axis_tangents(u)
    np.testing.assert_allclose(np.einsum("ni,ni->n", t[:, 0], u), 0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("ni,ni->n", t[:, 1], u), 0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(t, axis=-1), 1, atol=1e-14)
    np.testing.assert_allclose(np.cross(t[:, 0], t[:, 1]), u, atol=1e-14)
    np.testing.assert_allclose(axis_tangents([0, 0, 1]), [[1, 0, 0], [0, 1, 0]])


def test_tilt_is_exact_angle():
    model = load_model("puma")
    dx = np.zeros(33)
    dx[21] = 0.3  # u1.t1
    dx[22] = 0.4  # u1.t2
    axes, _, _ = perturbed_arrays(model, dx)
    ang = np.arccos(np.clip(axes[0] @ model.axes[0], -1, 1))
    assert ang == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(np.linalg.norm(axes, axis=-1), 1, atol=1e-14)


def test_bad_input():
    model = load_model("puma")
    with pytest.raises(InputError, match="q"):
        parameter_jacobian(model, np.zeros(5))
    with pytest.raises(InputError, match="dx"):
        apply_parameters(model, np.zeros(32))
    with pytest.raises(InputError, match="finite"):
        apply_parameters(model, np.full(33, np.nan))


def test_pose_error_is_first_order_in_dx():
    """pose_error - J dx shrinks quadratically with the step (second-order remainder)."""
    from zrp.kinematics.identification import pose_error

    model = load_model("puma")
    q = np.random.default_rng(0).uniform(-2, 2, (5, 6))
    space = parameter_space(model)
    base = np.random.default_rng(1).normal(size=space.size) * np.where(
        np.array(space.units) == "rad", 1e-3, 1.0)
    jac = parameter_jacobian(model, q)
    res = []
    for h in (1.0, 0.5, 0.25):
        actual, _ = apply_parameters(model, h * base)
        res.append(np.abs(pose_error(model, actual, q) - jac @ (h * base)).max())
    assert res[0] > 1e-9
    assert res[1] / res[0] == pytest.approx(0.25, rel=0.05)
    assert res[2] / res[1] == pytest.approx(0.25, rel=0.05)
