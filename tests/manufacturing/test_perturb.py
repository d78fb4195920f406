"""Eqs (8)-(12): percentage perturbations and the sign(0) convention."""

from __future__ import annotations

import numpy as np
import pytest

from zrp import load_model
from zrp.errors import InputError
from zrp.manufacturing.perturb import (
    PAPER_SIGN_ZERO,
    Perturbation,
    check_xi_percent,
    parse_parameter,
    perturb_axis,
    perturb_components,
    perturbation_names,
)


def test_xi_is_percent_and_eq11_closed_form():
    # b = (0, 254, 0), xi = 0.02 % -> (0, 254 + 0.02e-2 * 254, 0) with sign(0) = 0
    out = perturb_components([0.0, 254.0, 0.0], 0.02, sign_zero=0)
    np.testing.assert_allclose(out, [0.0, 254.0 * (1 + 2e-4), 0.0], rtol=1e-15)
    # sign(0) = +1 adds xi ||b|| to every component
    out = perturb_components([0.0, 254.0, 0.0], 0.02, sign_zero=1)
    np.testing.assert_allclose(out, [0.0508, 254.0508, 0.0508], rtol=1e-12)
    # negative components keep their sign and grow in magnitude
    out = perturb_components([3.0, -4.0, 0.0], 0.1, sign_zero=0)
    np.testing.assert_allclose(out, [3.005, -4.005, 0.0], rtol=1e-15)


def test_axis_sign_zero_conventions():
    u = np.array([0.0, 0.0, 1.0])
    # sign(0) = 0: (0, 0, 1 + xi) normalises back to u, the error vanishes (module docstring)
    np.testing.assert_array_equal(perturb_axis(u, 0.1, sign_zero=0), u)
    # sign(0) = +1: (xi, xi, 1 + xi)/norm, a tilt of atan(sqrt(2) xi / (1 + xi))
    xi = 1e-3
    up = perturb_axis(u, 0.1, sign_zero=1)
    np.testing.assert_allclose(up, np.array([xi, xi, 1 + xi]) / np.sqrt(2 * xi**2 + (1 + xi)**2))
    tilt = np.arccos(up @ u)
    assert tilt == pytest.approx(np.arctan(np.sqrt(2) * xi / (1 + xi)), rel=1e-9)
    # sign(0) = -1 tilts the other way by the same angle
    um = perturb_axis(u, 0.1, sign_zero=-1)
    assert np.arccos(um @ u) == pytest.approx(tilt, rel=1e-9)
    np.testing.assert_allclose(um[:2], -up[:2])


def test_defaults_are_the_papers_and_printed():
    p = Perturbation({"LE2": 0.02})
    assert (p.sign_zero_links, p.sign_zero_axes) == (0, 1) == (
        PAPER_SIGN_ZERO["links"], PAPER_SIGN_ZERO["axes"])
    assert "0 for link vectors" in p.convention and "+1 for joint axes" in p.convention


def test_apply_changes_only_the_named_parameter():
    model = load_model("puma")
    pm = Perturbation({"LE3": 0.05, "je4": -0.07}).apply(model)
    changed_b = np.flatnonzero(np.any(pm.bodies != model.bodies, axis=1))
    changed_u = np.flatnonzero(np.any(pm.axes != model.axes, axis=1))
    assert changed_b.tolist() == [2] and changed_u.tolist() == [3]
    assert np.linalg.norm(pm.bodies[2]) == pytest.approx(431.8 * (1 + 5e-4), rel=1e-14)
    np.testing.assert_allclose(np.linalg.norm(pm.axes, axis=1), 1.0, atol=1e-15)
    # LE7 is the end effector's body vector b_{7,0}
    pm7 = Perturbation.single("LE7", 0.1).apply(model)
    np.testing.assert_allclose(pm7.end_effector.body, [0, 0, -127 * 1.001])


@pytest.mark.parametrize("xi", [1.0, -1.0, 5, np.nan, np.inf, "a lot"])
def test_eq8_enforced_with_parameter_name(xi):
    with pytest.raises(InputError, match=r"LE2"):
        Perturbation({"LE2": xi})
    with pytest.raises(InputError, match="xi"):
        check_xi_percent(xi)


def test_unknown_names_and_bad_sign():
    model = load_model("puma")
    with pytest.raises(InputError, match="LE9"):
        Perturbation({"LE9": 0.02}).apply(model)
    with pytest.raises(InputError, match=r"JE7.*JE1\.\.JE6"):
        parse_parameter("JE7", model)
    with pytest.raises(InputError, match="XE1"):
        Perturbation({"XE1": 0.02})
    with pytest.raises(InputError, match="sign_zero_axes"):
        Perturbation({}, sign_zero_axes=2)
    with pytest.raises(InputError, match="given twice"):
        Perturbation({"LE2": 0.01, "le2": 0.02})
    assert perturbation_names(model)[:1] == ("LE1",) and perturbation_names(model)[-1] == "JE6"


# ---- properties (hypothesis) -------------------------------------------------------------
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_comp = st.one_of(st.just(0.0), st.floats(-500, 500, allow_nan=False).filter(
    lambda x: abs(x) > 1e-3))
_vec = st.tuples(_comp, _comp, _comp).map(np.array)
_xi = st.floats(-0.99, 0.99, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(v=_vec, xi=_xi, s0=st.sampled_from([-1, 0, 1]))
def test_eq11_change_has_closed_form_norm(v, xi, s0):
    """v' - v has |xi| ||v|| in every component that eq (11) touches, so ||v' - v|| =
    |xi|/100 ||v|| sqrt(m), m = nonzero components (all 3 when sign(0) != 0)."""
    d = perturb_components(v, xi, s0) - v
    m = 3 if s0 != 0 else np.count_nonzero(v)
    expected = abs(xi) / 100 * np.linalg.norm(v) * np.sqrt(m)
    assert np.linalg.norm(d) == pytest.approx(expected, rel=1e-9, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(v=_vec.filter(lambda v: np.linalg.norm(v) > 1e-2), xi=_xi, s0=st.sampled_from([1, -1]))
def test_eq9_axis_is_unit(v, xi, s0):
    u = v / np.linalg.norm(v)
    up = perturb_axis(u, xi, s0)
    assert np.linalg.norm(up) == pytest.approx(1.0, abs=1e-14)


@settings(max_examples=25, deadline=None)
@given(k=st.integers(1, 7), v=_vec, xi=_xi, seed=st.integers(0, 10_000))
def test_link_error_is_a_constant_translation_on_any_arm(k, v, xi, seed):
    """Whatever the arm and the joints, LE_k moves the tool by ||b_k' - b_k|| (eq 2 rotates
    b_k rigidly) and never rotates it."""
    from zrp.manufacturing.deviation import trajectory_deviation
    from zrp.model.manipulator import Manipulator

    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(6, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    bodies = rng.uniform(-300, 300, size=(7, 3))
    bodies[k - 1] = v
    model = Manipulator.from_arrays(axes, bodies, axial=[0, 0, 1], transverse=[1, 0, 0])
    q = rng.uniform(-np.pi, np.pi, size=(20, 6))
    dev = trajectory_deviation(model, Perturbation.single(f"LE{k}", xi), q)
    step = np.linalg.norm(perturb_components(v, xi, 0) - v)
    np.testing.assert_allclose(dev.delta_p, step, rtol=1e-7, atol=1e-9)
    # from_arrays renormalises the (unchanged) axes, which may move their last bit
    assert dev.max_angle_rad < 1e-14
