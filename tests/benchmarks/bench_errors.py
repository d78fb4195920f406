"""Benchmarks of the manufacturing-error analysis.

Goals (issue 3): the whole numerical example in < 1 s of compute; the Monte Carlo of 1e5
robots x 360 trajectory points in <= 5 s. Every timing is printed beside a baseline measured
in the same run on the same machine, so the ratios stay meaningful on a loaded machine.
Compilation (numba) is excluded: everything is warmed up first.

Run: python3 tests/benchmarks/bench_errors.py [--robots N] [--quick] [--out FILE.md] [--force]
(writes the tables to renders/benchmarks/bench_errors.md and .json; --quick: 1e4 robots).
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np
from _report import Report, add_output_arguments, output_path

import zrp
from zrp.kinematics.identification import apply_parameters, parameter_jacobian, parameter_space
from zrp.manufacturing.deviation import trajectory_deviation
from zrp.manufacturing.perturb import Perturbation
from zrp.manufacturing.population import monte_carlo
from zrp.manufacturing.study import PAPER_PARAMETERS, PAPER_XI
from zrp.manufacturing.tolerance import Tolerances
from zrp.paper.example import run_paper_example
from zrp.paper.scenario import circle_joint_path


def best_of(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def bench_paper(report: Report) -> None:
    model = zrp.load_model("puma")
    run_paper_example(model)  # warm-up (numba caches, imports)
    t_all = best_of(lambda: run_paper_example(model), 5)
    path = circle_joint_path(model, steps=360)

    def reference() -> None:  # the same 90 cells through Manipulator + NumPy deviations
        for name in PAPER_PARAMETERS:
            for xi in PAPER_XI:
                trajectory_deviation(model, Perturbation.single(name, xi), path.q, path.t)

    t_ref = best_of(reference, 3)
    ex = run_paper_example(model)
    print("numerical example (IK 360 steps + 10 x 9 study + alternative conventions + "
          "comparison):")
    print(f"  whole example    {t_all * 1e3:8.1f} ms   goal < 1000 ms -> "
          f"{'OK' if t_all < 1.0 else 'MISSED'}")
    for k, v in ex.timings_s.items():
        print(f"    {k:24s} {v * 1e3:8.2f} ms")
    print(f"  baseline: the 90 study cells via Perturbation.apply + trajectory_deviation "
          f"{t_ref * 1e3:.1f} ms; study kernel path is x{t_ref / ex.timings_s['study']:.1f} faster")
    report.table(
        "The paper's numerical example (IK 360 steps, 10 x 9 study cells, alternative "
        "conventions, comparison)", ["part", "time (ms)", "goal"],
        [("whole example, best of 5", f"{t_all * 1e3:.1f}", "< 1000"),
         *((f"of which {k}", f"{v * 1e3:.2f}", "") for k, v in ex.timings_s.items()
           if k != "total_compute"),  # the sum of the parts, not a part
         ("baseline: the 90 cells via Perturbation.apply + trajectory_deviation",
          f"{t_ref * 1e3:.1f}", f"study path x{t_ref / ex.timings_s['study']:.1f} faster")])


def bench_monte_carlo(n_robots: int, report: Report) -> None:
    model = zrp.load_model("puma")
    path = circle_joint_path(model, steps=359)  # 360 trajectory points
    q = path.q
    tol = Tolerances.build(model, length=0.02, angle_rad=5e-5)
    monte_carlo(model, q, tol, 256, rng=np.random.default_rng(0))  # warm-up
    t0 = time.perf_counter()
    mc = monte_carlo(model, q, tol, n_robots, rng=np.random.default_rng(1))
    wall = time.perf_counter() - t0
    poses = n_robots * q.shape[0]

    # baseline 1: the core batched kernel zrp.end_effector_pose on ONE model (no per-robot arrays)
    qq = np.tile(q, (10000 // q.shape[0] + 1, 1))[:10000]
    zrp.end_effector_pose(model, qq)
    t_fk = best_of(lambda: zrp.end_effector_pose(model, qq), 5)
    fk_rate = qq.shape[0] / t_fk
    # baseline 2: the straightforward per-robot loop (new Manipulator + end_effector_pose)
    space = parameter_space(model)
    dx = np.random.default_rng(2).uniform(-1, 1, (100, space.size)) * tol.values
    pd, _ = zrp.end_effector_pose(model, q)

    def per_robot() -> None:
        for i in range(dx.shape[0]):
            m, _ = apply_parameters(model, dx[i])
            p, _ = zrp.end_effector_pose(m, q)
            np.linalg.norm(p - pd, axis=1).max()

    t_loop = best_of(per_robot, 3)
    loop_rate = dx.shape[0] * q.shape[0] / t_loop
    print(f"\nMonte Carlo: {n_robots} robots x {q.shape[0]} points = {poses:.3g} poses "
          f"(numba threads: {numba.get_num_threads()})")
    print(f"  kernel           {mc.elapsed_s:8.3f} s  {mc.poses_per_s / 1e6:7.2f} M poses/s")
    print(f"  wall (incl. sampling, perturbed arrays) {wall:8.3f} s  "
          f"{poses / wall / 1e6:7.2f} M poses/s   goal <= 5 s -> "
          f"{'OK' if wall <= 5.0 else 'MISSED'}")
    print(f"  baseline zrp.end_effector_pose (one model, batched): {fk_rate / 1e6:.2f} M poses/s"
          f" -> Monte Carlo kernel x{mc.poses_per_s / fk_rate:.1f}")
    print(f"  baseline per-robot loop (Manipulator + end_effector_pose): "
          f"{loop_rate / 1e6:.3f} M poses/s -> x{mc.poses_per_s / loop_rate:.0f}")
    print(f"  P99 max delta_p = {mc.percentile(99)[0]:.4f} mm, P99 max angle = "
          f"{mc.percentile(99)[1]:.3e} rad")
    report.table(
        f"Monte Carlo: {n_robots} robots x {q.shape[0]} points (PUMA circle, 0.02 mm / 5e-5 rad "
        f"uniform; numba threads: {numba.get_num_threads()})",
        ["figure", "measured", "goal"],
        [("kernel", f"{mc.elapsed_s:.3f} s, {mc.poses_per_s / 1e6:.2f} M poses/s", ""),
         ("wall (incl. sampling, perturbed arrays)",
          f"{wall:.3f} s, {poses / wall / 1e6:.2f} M poses/s", "<= 5 s for 1e5 robots"),
         ("baseline zrp.end_effector_pose (one model, batched)",
          f"{fk_rate / 1e6:.2f} M poses/s", f"kernel x{mc.poses_per_s / fk_rate:.1f}"),
         ("baseline per-robot loop (Manipulator + end_effector_pose)",
          f"{loop_rate / 1e6:.3f} M poses/s", f"kernel x{mc.poses_per_s / loop_rate:.0f}"),
         ("P99 max delta_p, P99 max angle",
          f"{mc.percentile(99)[0]:.4f} mm, {mc.percentile(99)[1]:.3e} rad", "")])


def bench_sensitivity(report: Report) -> None:
    model = zrp.load_model("puma")
    path = circle_joint_path(model, steps=360)
    parameter_jacobian(model, path.q)
    t_an = best_of(lambda: parameter_jacobian(model, path.q), 5)
    space = parameter_space(model)

    def finite_differences() -> None:
        for i in range(space.size):
            d = np.zeros(space.size)
            d[i] = 1e-6
            for s in (1.0, -1.0):
                m, _ = apply_parameters(model, s * d)
                zrp.end_effector_pose(m, path.q)

    t_fd = best_of(finite_differences, 3)
    print(f"\nidentification Jacobian, {path.q.shape[0]} points x {space.size} parameters:")
    print(f"  analytic {t_an * 1e3:.2f} ms; baseline central finite differences "
          f"{t_fd * 1e3:.2f} ms -> x{t_fd / t_an:.1f}")
    report.table(
        f"Identification Jacobian, {path.q.shape[0]} points x {space.size} parameters",
        ["method", "time (ms)", "ratio"],
        [("analytic parameter_jacobian", f"{t_an * 1e3:.2f}", ""),
         ("baseline: central finite differences", f"{t_fd * 1e3:.2f}",
          f"analytic x{t_fd / t_an:.1f} faster")])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=None, help="Monte Carlo robots (1e5)")
    ap.add_argument("--quick", action="store_true", help="1e4 Monte Carlo robots")
    add_output_arguments(ap, "bench_errors")
    args = ap.parse_args()
    out = output_path(args)
    report = Report("bench_errors", "the manufacturing-error analysis: the paper's example, "
                    "Monte Carlo, identification Jacobian")
    bench_paper(report)
    bench_monte_carlo(args.robots or (10_000 if args.quick else 100_000), report)
    bench_sensitivity(report)
    report.write(out, args)


if __name__ == "__main__":
    main()
