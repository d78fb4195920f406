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
the previous result while the next is computed). Timings are the best of several rounds of
CPU time (process time), the calls compared timed in turn within each round (interleaved A/B
rounds, ``_timing.interleaved``), with the wall time and the load average beside them: the
rates and ratios are CPU-time figures, which a busy machine barely moves (wall-clock ones at
load 12 were 3-6x off).

Run: python3 tests/benchmarks/bench_kinematics.py [--quick] [--out FILE.md] [--force]
(writes the table to renders/benchmarks/bench_kinematics.md and .json; --quick: 1e5 poses).
"""

from __future__ import annotations

import argparse
import os

import mujoco
import numpy as np
from _report import Report, add_output_arguments, output_path
from _timing import Timing, interleaved

import zrp
from zrp.kinematics import _kernels as K
from zrp.kinematics._range_kernels import joint_limits
from zrp.kinematics.forward import _karrays

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def mujoco_loop(model: zrp.Manipulator, q: np.ndarray):
    """A Python loop of MuJoCo's ``mj_kinematics`` over ``q`` (the equivalent MJCF)."""
    import mjcf

    m = mjcf.build(model).model
    d = mujoco.MjData(m)
    n = q.shape[0]

    def run():
        for i in range(n):
            d.qpos[:] = q[i]
            mujoco.mj_kinematics(m, d)

    return run


def best(fn, repeat=5) -> Timing:
    return interleaved(fn, repeat=repeat)[0]


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

    n_mj = 20_000
    api_t, held_t, kern_t, mj_t = interleaved(
        lambda: zrp.end_effector_pose(model, q), api_held,
        lambda: K.fk_pose_batch(q, *arrays, lim, out), mujoco_loop(model, q[:n_mj]), repeat=7)
    t_api, t_held, t_kernel = api_t.cpu, held_t.cpu, kern_t.cpu
    numpy_t = best(lambda: zrp.forward_kinematics(model, q[: n // 10]), repeat=2)
    t_numpy = numpy_t.cpu * 10
    mj_rate = n_mj / mj_t.cpu
    api, kern = n / t_api, n / t_kernel

    def rate(t: Timing, count: int, unit: str = "M poses/s") -> str:
        return (f"{count / t.cpu / 1e6:.2f} {unit} (CPU; wall {count / t.wall / 1e6:.2f}, "
                f"load {t.load[0]:.1f}-{t.load[1]:.1f})")

    show("end_effector_pose (allocates output)", rate(api_t, n))
    show("end_effector_pose, previous result held", rate(held_t, n))
    show("compiled kernel, preallocated output", rate(kern_t, n), ">= 20")
    show("ratio API (fresh array) / kernel time", f"{t_api / t_kernel:.2f}x", "<= 1.2x")
    show("ratio API (result held) / kernel time", f"{t_held / t_kernel:.2f}x", "<= 1.2x")
    show("NumPy vectorised forward_kinematics", rate(numpy_t, n // 10))
    show("MuJoCo mj_kinematics, Python loop", rate(mj_t, n_mj))
    show("ratio kernel / MuJoCo loop", f"{kern / mj_rate:.1f}x", ">= 10x")
    show("ratio API / MuJoCo loop", f"{api / mj_rate:.1f}x", ">= 50x")
    show("ratio kernel / NumPy", f"{kern * t_numpy / n:.1f}x")

    jac = np.empty((n, 6, 6))
    jac_t, jk_t = interleaved(lambda: zrp.jacobian(model, q),
                              lambda: K.jac_batch(q, *arrays, lim, np.empty((0, 7)), jac),
                              repeat=3)
    show("jacobian (allocates output)", rate(jac_t, n, "M Jacobians/s"))
    show("compiled Jacobian kernel, preallocated", rate(jk_t, n, "M Jacobians/s"), ">= 5")

    setup = zrp.puma_circle()
    ik_t, ik_none_t = interleaved(
        lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000),
        lambda: zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000,
                                     correction="none"), repeat=10)
    t_ik, t_ik_none = ik_t.cpu, ik_none_t.cpu
    res = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 1000)
    show("circle IK, 1,000 steps, Newton", f"{t_ik * 1e3:.2f} ms CPU (wall "
         f"{ik_t.wall * 1e3:.2f} ms; max error {res.position_error.max():.1e} mm)", "<= 20 ms")
    show("circle IK, 1,000 steps, bare ABM4", f"{t_ik_none * 1e3:.2f} ms CPU (Newton / bare "
         f"{t_ik / t_ik_none:.2f})")
    report = Report("bench_kinematics", "forward kinematics, Jacobians and the circle IK "
                    "on one core")
    report.table(f"PUMA, {n:,} random poses (best of several interleaved rounds, CPU time)",
                 ["figure", "measured", "target"], rows,
                 note="Rates and ratios from CPU time (process time), the calls compared "
                      "timed in turn within each round; wall time and the 1-minute load "
                      "average of the rounds beside them.")
    report.write(out_md, args)


if __name__ == "__main__":
    main()
