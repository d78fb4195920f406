"""Worker-side reduction of the Monte Carlo (zrp.manufacturing.reduction): the merged
histograms bracket the percentiles of the full per-robot result of the same robots."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from zrp import load_model
from zrp.errors import InputError
from zrp.manufacturing import Histogram, Tolerances, monte_carlo, monte_carlo_summary
from zrp.manufacturing.histogram import geometric_edges


def _path(n: int, steps: int = 60) -> np.ndarray:
    t = np.linspace(0.0, 1.0, steps)
    return 0.8 * np.sin(2 * np.pi * t[:, None] + np.arange(n))


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_summary_brackets_the_full_result_of_the_same_robots(distribution):
    model = load_model("puma")
    q = _path(6)
    tol = Tolerances.build(model, length=0.05, angle_rad=1e-4)
    full = monte_carlo(model, q, tol, 3000, seed=7, chunk=700, distribution=distribution)
    red = monte_carlo_summary(model, q, tol, 3000, seed=7, chunk=700,
                              distribution=distribution)
    assert red.n_robots == 3000
    for h, x in ((red.delta_p, full.max_delta_p), (red.angle_rad, full.max_angle_rad)):
        assert h.maximum == x.max() and h.minimum == x.min()
        assert h.mean == pytest.approx(x.mean(), rel=1e-12)
        assert h.counts[0] == 0 and h.counts[-1] == 0  # the edges cover every robot
        for pct in (1.0, 50.0, 90.0, 99.0, 99.9):
            est, lo, hi = h.percentile(pct)
            exact = np.percentile(x, pct)
            assert lo <= exact <= hi and lo <= est <= hi
            # known to its bin, widened only by the gap between the two robots it interpolates
            xs = np.sort(x)
            k = (x.size - 1) * pct / 100
            gap = xs[int(np.ceil(k))] - xs[int(np.floor(k))]
            assert hi - lo <= gap + 2.5 * h.relative_width * hi
    s = red.summary()
    assert s["n_robots"] == 3000 and s["reduced_on_workers"]


def test_merge_order_does_not_matter_and_chunks_stay_small():
    model = load_model("puma")
    q = _path(6)
    tol = Tolerances.build(model, length=0.05, angle_rad=1e-4)
    here = monte_carlo_summary(model, q, tol, 2000, seed=3, chunk=300)
    with ThreadPoolExecutor(2) as ex:  # completion order differs from submission order
        there = monte_carlo_summary(model, q, tol, 2000, seed=3, chunk=300, executor=ex)
    for a, b in ((here.delta_p, there.delta_p), (here.angle_rad, there.angle_rad)):
        assert np.array_equal(a.counts, b.counts)
        assert (a.minimum, a.maximum) == (b.minimum, b.maximum)
    assert here.delta_p.counts.nbytes + here.delta_p.edges.nbytes < 70_000


def test_histogram_checks_and_exact_extremes():
    e = geometric_edges(1.0, 100.0, 4)
    h = Histogram.of([0.5, 2.0, 3.0, 250.0], e)
    assert list(h.counts) == [1, 2, 0, 0, 0, 1]  # edges 1, 3.16, 10, 31.6, 100
    assert h.percentile(100.0) == (250.0, 250.0, 250.0)
    assert h.percentile(0.0) == (0.5, 0.5, 0.5)
    with pytest.raises(InputError, match="finite values >= 0"):
        Histogram.of([1.0, np.nan], e)
    with pytest.raises(InputError, match="same edges"):
        h.merge(Histogram.of([1.0], geometric_edges(1.0, 10.0, 4)))
    with pytest.raises(InputError, match="0 < lo < hi"):
        geometric_edges(0.0, 1.0, 3)
    with pytest.raises(InputError, match="percentile"):
        h.percentile(101.0)


def test_tolerance_cli_reduced_brackets_the_gathered_run(capsys):
    from zrp.cli import main

    base = ["tolerance", "-n", "6000", "--steps", "40", "--no-progress", "--json"]
    assert main(base) == 0
    full = json.loads(capsys.readouterr().out)
    assert main([*base, "--reduce"]) == 0
    red = json.loads(capsys.readouterr().out)
    assert red["reduced_on_workers"] and "reduced_on_workers" not in full
    assert red["n_robots"] == full["n_robots"] == 6000
    # the same robots: every gathered percentile lies in the reduced bracket, the exact
    # maximum is the same, and the reduced CI contains the gathered one
    for parent_r, parent_f in ((red, full), (red["first_order"], full["first_order"])):
        for name in ("max_delta_p_mm", "max_angle_rad"):
            for key, exact in parent_f[name].items():
                lo, hi = parent_r[name][f"{key}_bracket"]
                assert lo <= exact <= hi, (name, key)
                assert hi - lo <= 0.02 * hi  # a few 0.56 % bins at most
    assert red["mc_max_over_worst_case_p"] == full["mc_max_over_worst_case_p"]
    (rlo, rhi), (flo, fhi) = red["p99_max_delta_p_ci95"], full["p99_max_delta_p_ci95"]
    assert rlo <= flo <= fhi <= rhi and rhi - rlo <= 1.05 * (fhi - flo) + 0.02 * rhi
    assert red["contribution"] == full["contribution"]


def test_tolerance_cli_reduces_above_the_gather_limit_and_allocate_refuses(monkeypatch, capsys):
    from zrp.cli import main
    from zrp.cli.commands import tolerance

    monkeypatch.setattr(tolerance, "GATHER_LIMIT", 1000)
    assert main(["tolerance", "-n", "1500", "--steps", "20", "--no-progress", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["reduced_on_workers"]
    assert main(["tolerance", "-n", "1000", "--steps", "20", "--no-progress", "--json"]) == 0
    assert "reduced_on_workers" not in json.loads(capsys.readouterr().out)
    assert main(["tolerance", "--allocate", "-n", "1500", "--steps", "20"]) == 2
    err = capsys.readouterr().err
    assert "--robots" in err and "at most 1,000 robots" in err


def test_reduced_histogram_bars_match_the_gathered_values():
    from zrp.manufacturing.plots import BARS, _bars

    model = load_model("puma")
    q = _path(6)
    tol = Tolerances.build(model, length=0.05, angle_rad=1e-4)
    full = monte_carlo(model, q, tol, 20000, seed=2)
    red = monte_carlo_summary(model, q, tol, 20000, seed=2)
    for h, x, scale in ((red.delta_p, full.max_delta_p, 1.0),
                        (red.angle_rad, full.max_angle_rad, 1e3)):
        left, width, count = _bars(h, scale)
        assert left.size == BARS and left[0] == x.min() * scale
        assert left[-1] + width[-1] == pytest.approx(x.max() * scale, rel=1e-12)
        assert count.sum() == pytest.approx(20000, rel=1e-12)
        exact, _ = np.histogram(x * scale, bins=np.append(left, left[-1] + width[-1]))
        # each bar is off only by the robots of the two fixed bins it cuts (spread uniformly)
        assert np.max(np.abs(count - exact)) <= 0.06 * exact.max()
        assert np.sum(np.abs(count - exact)) <= 0.02 * 20000
