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


def test_first_order_maxima_kernel_matches_numpy_products():
    # the compiled kernel against the plain definition: max_t || J(t) dx || per robot, by a
    # NumPy product of the whole (N, T, 6) deviations; N not a multiple of the block, zero
    # entries and an all-zero parameter column included
    from zrp.manufacturing.maxima import first_order_max

    rng = np.random.default_rng(11)
    jac = rng.normal(size=(37, 6, 9)) * (rng.random((37, 6, 9)) > 0.4)
    jac[:, :, 4] = 0.0
    dx = rng.normal(size=(130, 9))
    y = np.einsum("tkp,np->ntk", jac, dx)
    ref_r = np.linalg.norm(y[..., 0:3], axis=-1).max(axis=1)
    ref_p = np.linalg.norm(y[..., 3:6], axis=-1).max(axis=1)
    got_p, got_r = first_order_max(jac, dx)
    np.testing.assert_allclose(got_p, ref_p, rtol=1e-14)
    np.testing.assert_allclose(got_r, ref_r, rtol=1e-14)
    # each robot's value does not depend on the others in its block
    alone = first_order_max(jac, dx[77:78])
    assert alone[0][0] == got_p[77] and alone[1][0] == got_r[77]
    with pytest.raises(InputError, match=r"expected shapes \(T, 6, P\) and \(N, P\)"):
        first_order_max(jac, dx[:, :5])
