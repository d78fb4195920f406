"""The Monte Carlo chunk chosen from the work (zrp.manufacturing.chunks.chunk_size)."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.errors import InputError
from zrp.manufacturing import Tolerances, chunk_tasks, monte_carlo
from zrp.manufacturing.chunks import MAX_CHUNK, TASK_POSES, chunk_size


@pytest.mark.parametrize("n_robots, n_points, tasks", [
    (100_000, 360, 4), (10**9, 360, 36_000), (5000, 7, 4), (123_457, 1000, 16),
    (10**6, 360, 36), (1, 1, 1), (3, 10**8, 3)])
def test_chunk_size_cuts_the_work_into_a_multiple_of_4_tasks(n_robots, n_points, tasks):
    c = chunk_size(n_robots, n_points)
    assert -(-n_robots // c) == tasks  # ceil(N T / TASK_POSES) rounded up to 4 (<= N)
    assert c * n_points <= TASK_POSES + n_points  # no task above ~TASK_POSES poses


def test_chunk_size_of_the_benchmark_and_of_a_billion_robots():
    assert chunk_size(100_000, 360) == 25_000  # 4 tasks, 2 + 2 on two workers
    assert -(-10**9 // chunk_size(10**9, 360)) == 36_000
    assert chunk_size(10**7, 1) == MAX_CHUNK  # a short path: capped, not 1e7 robots a task


@pytest.mark.parametrize("bad", [(0, 360), (10, 0), (-1, 5)])
def test_chunk_size_refuses_empty_work(bad):
    with pytest.raises(InputError, match="n_robots, n_points"):
        chunk_size(*bad)


def test_default_chunk_is_chosen_from_the_work_and_is_deterministic():
    setup = zrp.puma_circle()
    q = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 59).q  # 60 points
    tol = Tolerances.build(setup.model, length=0.02, angle_rad=5e-5)
    tasks = chunk_tasks(setup.model, q, tol, 1000, seed=5)
    assert [t.size for t in tasks] == [250] * 4  # 6e4 poses: 1 task, rounded up to 4
    a = monte_carlo(setup.model, q, tol, 1000, seed=5)
    b = monte_carlo(setup.model, q, tol, 1000, seed=5, chunk=chunk_size(1000, 60))
    assert np.array_equal(a.max_delta_p, b.max_delta_p)
    assert np.array_equal(a.max_angle_rad, b.max_angle_rad)
