"""Checkpointed Monte Carlo (zrp.manufacturing.checkpoint): a run stopped part-way and resumed
ends with the same histograms, bit for bit, as one that was never stopped; the checkpoint only
resumes the run it holds."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from zrp import load_model
from zrp.errors import InputError, OutputExistsError
from zrp.manufacturing import Tolerances, monte_carlo_summary


def _setup():
    t = np.linspace(0.0, 1.0, 40)
    q = 0.8 * np.sin(2 * np.pi * t[:, None] + np.arange(6))
    model = load_model("puma")
    return model, q, Tolerances.build(model, length=0.05, angle_rad=1e-4)


class Interrupted(Exception):
    pass


class StopsAfter:
    """An executor whose task number ``n`` (0-based) fails: the run stops there."""

    def __init__(self, n: int) -> None:
        self.pool = ThreadPoolExecutor(2)
        self.n = n
        self.count = 0

    def submit(self, fn, *args):
        self.count += 1
        # the pool runs its queue in order: the failure comes after the first n chunks
        return self.pool.submit(fn if self.count <= self.n else _stop, *args)


def _stop(*_args):
    raise Interrupted("stopped")


def _same(a, b) -> None:
    for f in ("delta_p", "angle_rad", "first_order_delta_p", "first_order_angle_rad"):
        x, y = getattr(a, f), getattr(b, f)
        assert np.array_equal(x.counts, y.counts), f
        assert (x.total, x.minimum, x.maximum, x.sum, x.sumsq) == \
            (y.total, y.minimum, y.maximum, y.sum, y.sumsq), f


def test_a_stopped_run_resumes_to_the_uninterrupted_result(tmp_path):
    model, q, tol = _setup()
    args = dict(seed=5, chunk=250, first_order=True)
    whole = monte_carlo_summary(model, q, tol, 3000, **args)  # 12 chunks
    ck = tmp_path / "run.npz"
    with pytest.raises(Interrupted):
        monte_carlo_summary(model, q, tol, 3000, executor=StopsAfter(7), checkpoint=ck,
                            checkpoint_every_s=1e-9, **args)
    saved = np.load(ck)
    head = json.loads(str(saved["header"]))
    assert 0 < head["ready"] + len(head["waiting"]) < 12  # part of the run was kept
    with pytest.raises(OutputExistsError, match="resume=True"):
        monte_carlo_summary(model, q, tol, 3000, checkpoint=ck, **args)
    with ThreadPoolExecutor(2) as ex:
        resumed = monte_carlo_summary(model, q, tol, 3000, executor=ex, checkpoint=ck,
                                      resume=True, **args)
    _same(whole, resumed)
    assert resumed.resumed_robots == 250 * (head["ready"] + len(head["waiting"]))
    again = monte_carlo_summary(model, q, tol, 3000, checkpoint=ck, resume=True, **args)
    _same(whole, again)  # a finished run resumes to its result without running a chunk
    assert again.resumed_robots == 3000


def test_the_checkpoint_resumes_only_its_own_run(tmp_path):
    model, q, tol = _setup()
    ck = tmp_path / "run.npz"
    monte_carlo_summary(model, q, tol, 1000, seed=5, chunk=250, checkpoint=ck)
    with pytest.raises(InputError, match=r"another run \(different seed\)"):
        monte_carlo_summary(model, q, tol, 1000, seed=6, chunk=250, checkpoint=ck, resume=True)
    with pytest.raises(InputError, match="different robots, chunk"):
        monte_carlo_summary(model, q, tol, 2000, seed=5, chunk=500, checkpoint=ck, resume=True)
    other = Tolerances.build(model, length=0.04, angle_rad=1e-4)
    with pytest.raises(InputError, match="tolerances"):
        monte_carlo_summary(model, q, other, 1000, seed=5, chunk=250, checkpoint=ck,
                            resume=True)
    fresh = monte_carlo_summary(model, q, other, 1000, seed=5, chunk=250, checkpoint=ck,
                                resume=True, overwrite=True)
    assert fresh.resumed_robots == 0 and fresh.n_robots == 1000
    with pytest.raises(InputError, match="needs seed="):
        monte_carlo_summary(model, q, tol, 1000, rng=np.random.default_rng(1), chunk=250,
                            checkpoint=tmp_path / "b.npz")
    with pytest.raises(InputError, match=r"checkpoint_every_s: expected a finite number in \(0"):
        monte_carlo_summary(model, q, tol, 1000, seed=5, checkpoint=tmp_path / "c.npz",
                            checkpoint_every_s=0.0)
    (tmp_path / "junk.npz").write_bytes(b"not an archive")
    with pytest.raises(InputError, match="not a Monte Carlo checkpoint"):
        monte_carlo_summary(model, q, tol, 1000, seed=5, checkpoint=tmp_path / "junk.npz",
                            resume=True)


def test_tolerance_cli_checkpoint_and_resume(tmp_path, capsys):
    from zrp.cli import main

    ck = str(tmp_path / "run.npz")
    base = ["tolerance", "-n", "2000", "--steps", "20", "--no-progress", "--json"]
    assert main([*base, "--reduce"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert main([*base, "--checkpoint", ck]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main([*base, "--checkpoint", ck]) == 2
    assert "--resume continues it, --force starts over" in capsys.readouterr().err
    assert main([*base, "--checkpoint", ck, "--resume"]) == 0
    resumed = json.loads(capsys.readouterr().out)
    assert resumed["resumed_robots"] == 2000 and first["resumed_robots"] == 0
    for k in ("max_delta_p_mm", "max_angle_rad", "first_order", "p99_max_delta_p_ci95"):
        assert plain[k] == first[k] == resumed[k], k
    assert main([*base, "--resume"]) == 2
    assert "--resume" in capsys.readouterr().err
    assert main([*base, "--checkpoint", str(tmp_path / "run.txt")]) == 2
    assert "not a .npz file name" in capsys.readouterr().err
