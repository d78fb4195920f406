"""Kinematics benchmark: forward kinematics, Jacobian and the circle IK (one core).

Prints, in one run:
* batched forward kinematics of N = 1e6 random PUMA poses (p and Euler-Rodrigues parameters)
  through ``zrp.end_effector_pose`` and through the bare compiled kernel into a preallocated
  buffer, against a Python loop of MuJoCo's ``mj_kinematics`` on the equivalent MJCF model
  (the loop is timed on a subset and scaled), and the ratio;
* the vectorised NumPy forward kinematics (``zrp.forward_kinematics``), the pre-compilation
  baseline;
* batched Jacobians per second;
* the 125 mm circle inverse kinematics with 1,000 steps.

Targets on the 2-core machine: >= 20 M poses/s (>= 10x the MuJoCo loop), >= 5 M Jacobians/s,
circle IK of 1,000 steps <= 20 ms. Timings are the best of several repeats.
"""

from __future__ import annotations

import os
import time

import mujoco
import numpy as np

import zrp
from zrp.kinematics import _kernels as K
from zrp.kinematics._range_kernels import joint_limits
from zrp.kinematics.forward import _karrays

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def best(fn, repeat=5):
    fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def mujoco_loop_rate(model: zrp.Manipulator, q: np.ndarray) -> float:
    import mjcf

    m = mjcf.build(model).model
    d = mujoco.MjData(m)
    n = q.shape[0]

    def run():
        for i in range(n):
            d.qpos[:] = q[i]
            mujoco.mj_kinematics(m, d)

    return n / best(run, repeat=3)


def main() -> None:
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    n = 1_000_000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    print(f"zrp forward kinematics, PUMA, N = {n:,} poses, one core")

    t_api = best(lambda: zrp.end_effector_pose(model, q))
    out = np.empty((n, 7))
    arrays = _karrays(model)
    lim = joint_limits(model)
    t_kernel = best(lambda: K.fk_pose_batch(q, *arrays, lim, out))
    t_numpy = best(lambda: zrp.forward_kinematics(model, q[:100_000]), repeat=2) * 10
    mj_rate = mujoco_loop_rate(model, q[:20_000])
    api, kern = n / t_api, n / t_kernel
    print(f"  end_effector_pose (allocates output) {api / 1e6:8.2f} M poses/s")
    print(f"  compiled kernel, preallocated output {kern / 1e6:8.2f} M poses/s  (target >= 20)")
    print(f"  NumPy vectorised forward_kinematics  {n / t_numpy / 1e6:8.2f} M poses/s")
    print(f"  MuJoCo mj_kinematics, Python loop    {mj_rate / 1e6:8.3f} M poses/s")
    print(f"  ratio kernel / MuJoCo loop           {kern / mj_rate:8.1f}x  (target >= 10x)")
    print(f"  ratio API / MuJoCo loop              {api / mj_rate:8.1f}x")
    print(f"  ratio kernel / NumPy                 {kern * t_numpy / n:8.1f}x")

    t_jac = best(lambda: zrp.jacobian(model, q), repeat=3)
    jac = np.empty((n, 6, 6))
    t_jk = best(lambda: K.jac_batch(q, *arrays, lim, np.empty((0, 7)), jac), repeat=3)
    print(f"  jacobian (allocates output)          {n / t_jac / 1e6:8.2f} M Jacobians/s")
    print(f"  compiled kernel, preallocated output {n / t_jk / 1e6:8.2f} M Jacobians/s"
          "  (target >= 5)")

    setup = zrp.puma_circle()
    t_ik = best(lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000),
                repeat=10)
    t_ik_none = best(lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0,
                                                  1000, correction="none"), repeat=10)
    res = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000)
    print(f"  circle IK, 1,000 steps, Newton       {t_ik * 1e3:8.2f} ms  (target <= 20 ms; "
          f"max error {res.position_error.max():.1e} mm)")
    print(f"  circle IK, 1,000 steps, bare ABM4    {t_ik_none * 1e3:8.2f} ms  "
          f"(ratio Newton / bare {t_ik / t_ik_none:.2f})")


if __name__ == "__main__":
    main()
