"""Euler-Rodrigues algebra against scipy's Rotation and closed forms."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from zrp.rotations import rodrigues as er

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


def _rand_er(rng, shape):
    e = rng.normal(size=(*shape, 4))
    return e / np.linalg.norm(e, axis=-1, keepdims=True)


def test_axis_angle_is_unit_and_matches_scipy(rng):
    u = rng.normal(size=(50, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    th = rng.uniform(-7, 7, 50)
    e = er.er_from_axis_angle(u, th)
    np.testing.assert_allclose(np.linalg.norm(e, axis=1), 1.0, atol=1e-15)
    ref = Rotation.from_rotvec(u * th[:, None]).as_matrix()
    np.testing.assert_allclose(er.matrix_from_er(e), ref, atol=1e-14)


def test_composition_equals_matrix_product(rng):
    a, b = _rand_er(rng, (100,)), _rand_er(rng, (100,))
    ab = er.er_multiply(a, b)
    np.testing.assert_allclose(np.linalg.norm(ab, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(er.matrix_from_er(ab), er.matrix_from_er(a) @ er.matrix_from_er(b),
                               atol=1e-14)


def test_rotate_matches_matrix_and_scipy(rng):
    e = _rand_er(rng, (20,))
    v = rng.normal(size=(20, 3))
    out = er.er_rotate(e, v)
    np.testing.assert_allclose(out, np.einsum("nij,nj->ni", er.matrix_from_er(e), v), atol=1e-13)
    ref = Rotation.from_quat(er.scipy_quat_from_er(e)).apply(v)
    np.testing.assert_allclose(out, ref, atol=1e-13)


def test_from_matrix_round_trip_including_half_turns(rng):
    e = _rand_er(rng, (200,))
    # add exact half turns (e0 = 0) and identity, the hard cases for matrix -> parameters
    e = np.concatenate([e, [[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [1, 0, 0, 0]]])
    back = er.er_from_matrix(er.matrix_from_er(e))
    same = np.minimum(np.abs(back - e).max(axis=1), np.abs(back + e).max(axis=1))
    assert same.max() < 1e-14


def test_angle_rotvec_and_paper_delta_r():
    th = np.array([0.0, 1e-9, 0.3, 2.0, np.pi])
    e = er.er_from_axis_angle(np.array([0.0, 0.0, 1.0]), th)
    np.testing.assert_allclose(er.er_angle(e), th, atol=1e-15)
    np.testing.assert_allclose(er.rotvec_from_er(e)[:, 2], th, atol=1e-15)
    # eq (15): sqrt(4 (1 - cos^2 + sin^2)) = 2 sqrt(2) sin(theta/2)
    np.testing.assert_allclose(er.er_delta_r(e), 2 * np.sqrt(2) * np.sin(th / 2), atol=1e-15)


def test_rotvec_round_trip(rng):
    rv = rng.normal(size=(100, 3))
    rv = rv / np.linalg.norm(rv, axis=1, keepdims=True) * rng.uniform(0, 3.1, (100, 1))
    np.testing.assert_allclose(er.rotvec_from_er(er.er_from_rotvec(rv)), rv, atol=1e-14)
    np.testing.assert_allclose(er.er_from_rotvec(rv),
                               er.er_from_scipy_quat(Rotation.from_rotvec(rv).as_quat()),
                               atol=1e-14)


def test_conjugate_is_inverse(rng):
    e = _rand_er(rng, (10,))
    np.testing.assert_allclose(er.er_multiply(e, er.er_conjugate(e)), er.er_identity((10,)),
                               atol=1e-15)


@settings(max_examples=60, deadline=None)
@given(arrays(float, (2, 4), elements=finite), arrays(float, 3, elements=finite))
def test_property_rotation_preserves_length_and_composes(q, v):
    norms = np.linalg.norm(q, axis=1)
    if np.any(norms < 1e-3):
        return
    e = q / norms[:, None]
    r1 = er.er_rotate(e[1], v)
    np.testing.assert_allclose(np.linalg.norm(r1), np.linalg.norm(v), rtol=1e-12, atol=1e-12)
    lhs = er.er_rotate(er.er_multiply(e[0], e[1]), v)
    rhs = er.er_rotate(e[0], r1)
    np.testing.assert_allclose(lhs, rhs, atol=1e-11)


@pytest.mark.parametrize("shape", [(), (3,), (2, 5)])
def test_batching_over_leading_axes(rng, shape):
    e = _rand_er(rng, shape)
    assert er.matrix_from_er(e).shape == (*shape, 3, 3)
    assert er.er_multiply(e, e).shape == (*shape, 4)
    assert er.er_angle(e).shape == shape
