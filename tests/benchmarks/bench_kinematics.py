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
circle IK of 1,000 steps <= 20 ms; the public call into a fresh array within 1.2x of its
kernel and >= 50x the MuJoCo loop (a fresh result reuses a recycled buffer,
``zrp.arrays.recycled_empty``: both the result dropped at once and the usual loop that holds
the previous result while the next is computed). Timings are the best of several repeats,
the calls timed in turn (interleaved) so that a busy machine slows them alike.

Run: python3 tests/benchmarks/bench_kinematics.py [--quick] [--out FILE.md] [--force]
(writes the table to renders/benchmarks/bench_kinematics.md and .json; --quick: 1e5 poses).
"""

from __future__ import annotations

import argparse
import os
import time

import mujoco
import numpy as np
from _report import Report, add_output_arguments, output_path

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


def best_interleaved(*fns, repeat=9):
    """Best time of each of ``fns``, timed in turn within each repeat."""
    for fn in fns:
        fn()
    times = [[] for _ in fns]
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            times[i].append(time.perf_counter() - t)
    return [min(t) for t in times]


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
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e5 poses instead of 1e6")
    add_output_arguments(ap, "bench_kinematics")
    args = ap.parse_args()
    out_md = output_path(args)
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    n = 100_000 if args.quick else 1_000_000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    print(f"zrp forward kinematics, PUMA, N = {n:,} poses, one core")
    rows: list[tuple[str, str, str]] = []

    def show(label: str, value: str, target: str = "") -> None:
        rows.append((label, value, target))
        print(f"  {label:<36} {value}" + (f"  (target {target})" if target else ""))

    out = np.empty((n, 7))
    arrays = _karrays(model)
    lim = joint_limits(model)
    held = {}

    def api_held():  # the usual loop: the previous result is held while the next is computed
        held["p"], held["er"] = zrp.end_effector_pose(model, q)

    t_api, t_held, t_kernel = best_interleaved(
        lambda: zrp.end_effector_pose(model, q), api_held,
        lambda: K.fk_pose_batch(q, *arrays, lim, out))
    t_numpy = best(lambda: zrp.forward_kinematics(model, q[: n // 10]), repeat=2) * 10
    mj_rate = mujoco_loop_rate(model, q[:20_000])
    api, kern = n / t_api, n / t_kernel
    show("end_effector_pose (allocates output)", f"{api / 1e6:.2f} M poses/s")
    show("end_effector_pose, previous result held", f"{n / t_held / 1e6:.2f} M poses/s")
    show("compiled kernel, preallocated output", f"{kern / 1e6:.2f} M poses/s", ">= 20")
    show("ratio API (fresh array) / kernel time", f"{t_api / t_kernel:.2f}x", "<= 1.2x")
    show("ratio API (result held) / kernel time", f"{t_held / t_kernel:.2f}x", "<= 1.2x")
    show("NumPy vectorised forward_kinematics", f"{n / t_numpy / 1e6:.2f} M poses/s")
    show("MuJoCo mj_kinematics, Python loop", f"{mj_rate / 1e6:.3f} M poses/s")
    show("ratio kernel / MuJoCo loop", f"{kern / mj_rate:.1f}x", ">= 10x")
    show("ratio API / MuJoCo loop", f"{api / mj_rate:.1f}x", ">= 50x")
    show("ratio kernel / NumPy", f"{kern * t_numpy / n:.1f}x")

    t_jac = best(lambda: zrp.jacobian(model, q), repeat=3)
    jac = np.empty((n, 6, 6))
    t_jk = best(lambda: K.jac_batch(q, *arrays, lim, np.empty((0, 7)), jac), repeat=3)
    show("jacobian (allocates output)", f"{n / t_jac / 1e6:.2f} M Jacobians/s")
    show("compiled Jacobian kernel, preallocated", f"{n / t_jk / 1e6:.2f} M Jacobians/s",
         ">= 5")

    setup = zrp.puma_circle()
    t_ik = best(lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000),
                repeat=10)
    t_ik_none = best(lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0,
                                                  1000, correction="none"), repeat=10)
    res = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000)
    show("circle IK, 1,000 steps, Newton", f"{t_ik * 1e3:.2f} ms (max error "
         f"{res.position_error.max():.1e} mm)", "<= 20 ms")
    show("circle IK, 1,000 steps, bare ABM4", f"{t_ik_none * 1e3:.2f} ms (Newton / bare "
         f"{t_ik / t_ik_none:.2f})")
    report = Report("bench_kinematics", "forward kinematics, Jacobians and the circle IK "
                    "on one core")
    report.table(f"PUMA, {n:,} random poses (best of several repeats)",
                 ["figure", "measured", "target"], rows)
    report.write(out_md, args)


if __name__ == "__main__":
    main()
