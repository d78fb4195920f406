"""A held direction's reading in the arm's terms (zrp.gap.fit.heldname): a common tilt of the
proximal axes is read as the distal axes tilted against them, only when one rotation explains
the tilts (built here with SciPy's rotations, independently of the code's cross products)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

import zrp
from tests.gap.test_wellposed import ur_like
from zrp.gap.fit.heldname import read_tilts

W = np.array([1.3e-3, -0.4e-3, 0.2e-3])  # rad, a rotation that tilts every UR axis


def _axes() -> np.ndarray:
    return np.array(ur_like().axes, dtype=float)


def _block_tilts(k: int, omega=W) -> np.ndarray:
    """Tilts of the UR axes when axes 1..k turn together by ``omega`` (the others stay)."""
    axes = _axes()
    du = np.zeros_like(axes)
    du[:k] = Rotation.from_rotvec(omega).apply(axes[:k]) - axes[:k]
    return du


def test_a_common_tilt_of_axes_1_to_5_reads_as_axis_6_tilted_against_them():
    assert read_tilts(_axes(), _block_tilts(5)).startswith("axis 6 tilted against axes 1-5 ")
    assert read_tilts(_axes(), _block_tilts(4)).startswith("axes 5-6 tilted against axes 1-4 ")


def test_no_reading_where_one_rotation_does_not_explain_the_tilts():
    axes = _axes()
    rng = np.random.default_rng(1)
    du = _block_tilts(5)
    du[1] = 1e-3 * np.cross(axes[1], rng.normal(size=3))  # axis 2 tilted its own way
    assert read_tilts(axes, du) == ""
    assert read_tilts(axes, _block_tilts(1)) == ""       # one axis: already its own name
    assert read_tilts(axes, _block_tilts(6)) == ""       # every axis: no distal part
    du = _block_tilts(5)
    du[5] = 0.5 * (Rotation.from_rotvec(W).apply(axes[5]) - axes[5])  # axis 6 tilted too
    assert read_tilts(axes, du) == ""
    # a rotation about y turns axis 6 (along y) about itself only: no tilt of it to name
    assert read_tilts(axes, _block_tilts(5, np.array([0.0, 1e-3, 0.0]))) == ""


def test_the_reading_is_the_same_arm_up_to_a_rotation_of_the_whole():
    """Axes 1-5 and their links turned by R measure as axis 6, its links and the tool turned
    by R^T, the whole seen through R (the registration): forward kinematics, random q."""
    m = ur_like()
    axes, bodies = np.array(m.axes, float), np.array(m.bodies, float)
    R = Rotation.from_rotvec(W).as_matrix()
    tool = np.array([0.0, 60.0, 40.0])
    a_axes, a_bodies = axes.copy(), bodies.copy()
    a_axes[:5], a_bodies[:5] = axes[:5] @ R.T, bodies[:5] @ R.T
    b_axes, b_bodies = axes.copy(), bodies.copy()
    b_axes[5:], b_bodies[5:] = axes[5:] @ R, bodies[5:] @ R
    q = np.random.default_rng(0).uniform(-2.0, 2.0, (20, 6))
    fa = zrp.forward_kinematics(m.with_arrays(axes=a_axes, bodies=a_bodies), q)
    fb = zrp.forward_kinematics(m.with_arrays(axes=b_axes, bodies=b_bodies), q)
    pa = fa.position + fa.rotation @ tool
    pb = fb.position + fb.rotation @ (R.T @ tool)
    assert np.abs(pa - pb @ R.T).max() < 1e-9
    assert np.abs(pa - pb).max() > 1e-2  # without the registration's R they differ
