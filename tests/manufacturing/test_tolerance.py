"""Monte Carlo kernel, first-order model, worst-case bound and tolerance allocation."""

from __future__ import annotations

import numpy as np
import pytest

from zrp import load_model
from zrp.errors import InputError
from zrp.manufacturing import (
    Tolerances,
    allocate_tolerances,
    apply_parameters,
    draw_parameters,
    monte_carlo,
    parameter_jacobian,
    percentile_ci,
    tolerance_report,
    worst_case_bound,
)
from zrp.manufacturing.deviation import pose_deviation


def _path(n: int, steps: int = 120, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, steps)
    return rng.uniform(0.3, 2.0, n) * np.sin(2 * np.pi * t[:, None] + rng.uniform(0, 6, n))


@pytest.mark.parametrize("name,offsets", [("puma", False), ("puma", True), ("scara", True)])
def test_kernel_matches_reference_deviation(name, offsets):
    """The compiled kernel's per-robot maxima equal the NumPy reference of eqs (15)-(17)."""
    model = load_model(name)
    q = _path(model.n)
    if name == "scara":
        q[:, 2] = 50 + 40 * np.abs(q[:, 2])  # prismatic stroke in mm
    tol = Tolerances.build(model, length=0.5, angle_rad=2e-3, offset=1e-3,
                           joint_offsets=offsets)
    rng = np.random.default_rng(3)
    mc = monte_carlo(model, q, tol, 5, rng=rng)
    dx = draw_parameters(tol, 5, "uniform", np.random.default_rng(3))
    for i in range(5):
        actual, off = apply_parameters(model, dx[i], joint_offsets=offsets)
        dev = pose_deviation(model, actual, q, q_offset=off)
        assert mc.max_delta_p[i] == pytest.approx(dev.max_delta_p, rel=1e-11)
        assert mc.max_angle_rad[i] == pytest.approx(dev.max_angle_rad, rel=1e-8)


def test_small_tolerances_match_first_order_percentiles():
    model = load_model("puma")
    q = _path(6, seed=1)
    tol = Tolerances.build(model, length=0.01, angle_rad=2e-5)
    mc = monte_carlo(model, q, tol, 3000, rng=np.random.default_rng(5), first_order=True)
    for pct in (50, 90, 99):
        assert np.percentile(mc.max_delta_p, pct) == pytest.approx(
            np.percentile(mc.first_order_delta_p, pct), rel=1e-3)
        assert np.percentile(mc.max_angle_rad, pct) == pytest.approx(
            np.percentile(mc.first_order_angle_rad, pct), rel=1e-3)
    # larger tolerances: the second-order terms show up but stay small
    big = monte_carlo(model, q, tol.scaled(200.0), 500, rng=np.random.default_rng(5),
                      first_order=True)
    rel = np.abs(big.max_delta_p / big.first_order_delta_p - 1)
    assert rel.max() > 1e-4 and np.median(rel) < 0.05


def test_worst_case_bound_holds_and_is_tight_for_one_parameter():
    model = load_model("puma")
    q = _path(6, seed=2)
    tol = Tolerances.build(model, length=0.02, angle_rad=5e-5)
    jac = parameter_jacobian(model, q)
    wc_p, wc_r = worst_case_bound(jac, tol.values)
    mc = monte_carlo(model, q, tol, 2000, rng=np.random.default_rng(0))
    assert mc.max_delta_p.max() <= wc_p.max() * (1 + 1e-6)
    assert mc.max_angle_rad.max() <= wc_r.max() * (1 + 1e-6)
    # one tilt alone: the bound is attained at the corner dx = +tol
    only = Tolerances.build(model, per_parameter={"u2.t1": 1e-5})
    wc_p1, _ = worst_case_bound(jac, only.values)
    actual, _ = apply_parameters(model, only.values)
    dev = pose_deviation(model, actual, q)
    assert dev.max_delta_p == pytest.approx(wc_p1.max(), rel=1e-4)


def test_normal_draws_use_three_sigma():
    model = load_model("puma")
    tol = Tolerances.build(model, length=0.3, angle_rad=0.0)
    dx = draw_parameters(tol, 40000, "normal", np.random.default_rng(0))
    assert dx[:, 0].std() == pytest.approx(0.1, rel=0.02)
    assert np.all(dx[:, 21:] == 0)
    du = draw_parameters(tol, 40000, "uniform", np.random.default_rng(0))
    assert np.abs(du[:, :21]).max() <= 0.3 and du[:, 0].std() == pytest.approx(
        0.3 / np.sqrt(3), rel=0.02)


def test_percentile_ci_brackets_the_percentile():
    x = np.random.default_rng(0).normal(size=20000)
    lo, hi = percentile_ci(x, 99)
    assert lo < np.percentile(x, 99) < hi
    assert lo < 2.326 < hi  # the true 99th percentile of N(0, 1)


def test_allocation_meets_requirement_and_beats_equal_tolerances():
    model = load_model("puma")
    q = _path(6, steps=60, seed=4)
    al = allocate_tolerances(model, q, rng=np.random.default_rng(1), max_delta_p=0.1,
                             percentile=99, n_search=1500, n_verify=4000)
    assert al.verified
    assert al.verification.percentile(99)[0] <= 0.1
    # the search landed close to the requirement (it is not needlessly tight)
    assert al.verification.percentile(99)[0] > 0.9 * 0.1
    assert al.looseness_mm >= al.baseline_looseness_mm
    # an independent Monte Carlo with another seed agrees within its sampling error
    check = monte_carlo(model, q, al.tolerances, 4000, rng=np.random.default_rng(99))
    assert check.percentile(99)[0] < 0.1 * 1.03


def test_report_and_errors():
    model = load_model("puma")
    q = _path(6)
    tol = Tolerances.build(model, length=0.02, angle_rad=5e-5, per_parameter={"b1.*": 0})
    assert tol.values[:3].tolist() == [0, 0, 0]
    rep = tolerance_report(model, q, tol)
    assert rep["contribution"].names[0] != "b1.x"
    assert abs(sum(rep["contribution"].share_p) - 100) < 1e-9
    with pytest.raises(InputError, match="zz"):
        Tolerances.build(model, per_parameter={"zz*": 1})
    with pytest.raises(InputError, match="length"):
        Tolerances.build(model, length=-1)
    with pytest.raises(InputError, match="distribution"):
        monte_carlo(model, q, tol, 10, rng=np.random.default_rng(0), distribution="cauchy")
    with pytest.raises(InputError, match="n_robots"):
        monte_carlo(model, q, tol, 0, rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="another model"):
        monte_carlo(load_model("scara"), _path(4), tol, 10, rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="percentile"):
        monte_carlo(model, q, tol, 10, rng=np.random.default_rng(0)).percentile(150)
    with pytest.raises(InputError, match="rng"):
        draw_parameters(tol, 3, "uniform", 42)
    with pytest.raises(InputError, match="requirement"):
        allocate_tolerances(model, q, rng=np.random.default_rng(0), max_delta_p=None)
