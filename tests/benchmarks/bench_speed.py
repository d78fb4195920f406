"""Speed against the issue-15 targets, every figure beside a baseline measured in the same run.

Run: python3 tests/benchmarks/bench_speed.py [--quick] [--only diagnosis|single]
[--out FILE.md] [--force]   (from the repository root; writes the table to
renders/benchmarks/bench_speed.md and .json, bench_speed_<only>.md with --only)

One core for the kernels (NUMBA_NUM_THREADS=1, set before numba loads). Prints one table:
figure, measured value, target, the baseline of the same run and the ratio:

* batched FK kernel (1e6 PUMA poses) and the API; baseline: the kernel (API within 1.2x);
* batched Jacobians; baseline: the FK kernel (a Jacobian needs ~2.5x the work of a pose);
* one FK call and one Jacobian from Python (CPU time per call, interleaved rounds,
  ``_timing``); baselines: Pinocchio (``pin``) forwardKinematics + updateFramePlacements (the
  target: within 2x) and forwardKinematics alone / computeJointJacobians + getJointJacobian,
  MuJoCo mj_kinematics / mj_kinematics + mj_comPos + mj_jacBody, on the same arm (where
  installed);
* Monte Carlo 1e5 robots x 360 points on one core (baseline: the FK kernel's rate), gathered
  and reduced on the workers (histograms); then on a Dask LocalCluster of 1 and of 2 workers
  (baseline: 1 worker; the chunk chosen from the work, zrp.manufacturing.chunks.chunk_size);
* the full diagnosis of the IRB 120 laser-tracker data in ../shared (2,946 points) and of its
  first 999 points; baselines: the registration fit alone, the same diagnosis with the
  Levenberg-Marquardt fits on the tall Jacobian (the former: MINPACK's own QR of it instead
  of the QR-compressed problem, zrp.gap.model.problem.compressed) and on OpenBLAS's own threads
  (the former; zrp/blas.py) (skipped without ../shared);
* the blind benchmark's simulation of a 200-pose scenario; baselines: the same poses measured
  by forward kinematics only, and the former procedure (every move to a pre-pose simulated).
"""

from __future__ import annotations

import os

os.environ["NUMBA_NUM_THREADS"] = "1"  # one core: must precede the first numba import

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

# measure the checkout this script is in, not whichever copy is installed (an editable
# install of another checkout would otherwise be imported)
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from _report import Report, add_output_arguments, output_path
from _timing import Timing, interleaved

import zrp
from zrp.kinematics import _kernels as K
from zrp.kinematics._range_kernels import joint_limits
from zrp.kinematics.forward import _karrays
from zrp.rotations.rodrigues import matrix_from_er

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "irb120-lasertracker"
ROWS: list[tuple[str, str, str, str, str]] = []


def row(what: str, value: str, target: str, baseline: str, ratio: str) -> None:
    ROWS.append((what, value, target, baseline, ratio))
    print(f"  {what:<44} {value:>14}  target {target:<12} baseline {baseline:<28} {ratio}",
          flush=True)


def best(*fns, repeat=5):
    """Best wall time of each function, measured interleaved (the load changes within
    seconds); one function -> a float, several -> a list."""
    for fn in fns:
        fn()
    out: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for times, fn in zip(out, fns, strict=True):
            t = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t)
    mins = [min(t) for t in out]
    return mins[0] if len(fns) == 1 else mins


def per_call(*fns, number=20000, repeat=9) -> list[Timing]:
    """Best time per call of each function: CPU time (process time) of ``number`` calls in a
    loop, the functions timed in turn within each round (_timing.interleaved), the wall time
    and the load average beside it."""
    def loop(fn):
        def run():
            for _ in range(number):
                fn()
        return run

    return [Timing(t.cpu / number, t.wall / number, t.load)
            for t in interleaved(*(loop(fn) for fn in fns), repeat=repeat)]


def _us(t: Timing) -> str:
    return f"{t.cpu * 1e6:.2f}"


def batched(model: zrp.Manipulator, n: int) -> float:
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, model.n))
    arrays = _karrays(model)
    lim = joint_limits(model)
    out = np.empty((n, 7))
    buf = np.empty((n, 7))
    t_k, t_buf, t_api = best(lambda: K.fk_pose_batch(q, *arrays, lim, out),
                             lambda: zrp.end_effector_pose(model, q, out=buf),
                             lambda: zrp.end_effector_pose(model, q), repeat=7)
    jac = np.empty((n, 6, model.n))
    t_j, t_japi = best(lambda: K.jac_batch(q, *arrays, lim, np.empty((0, 7)), jac),
                       lambda: zrp.jacobian(model, q), repeat=4)
    row("batched FK, kernel (M poses/s/core)", f"{n / t_k / 1e6:.1f}", ">= 50", "-", "")
    # like for like: the kernel writes into a buffer it reuses, so does the API with out=
    row("batched FK, end_effector_pose(out=) (M/s)", f"{n / t_buf / 1e6:.1f}",
        "<= 1.2x kernel", f"kernel {n / t_k / 1e6:.1f} M/s", f"{t_buf / t_k:.2f}x")
    row("  the same into a fresh array (M/s)", f"{n / t_api / 1e6:.1f}", "<= 1.2x kernel",
        f"kernel {n / t_k / 1e6:.1f} M/s", f"{t_api / t_k:.2f}x (a recycled buffer)")
    row("batched Jacobian, kernel (M/s)", f"{n / t_j / 1e6:.1f}", ">= 15",
        f"FK kernel {n / t_k / 1e6:.1f} M/s", f"{t_j / t_k:.2f}x the FK time")
    row("batched Jacobian, jacobian() (M/s)", f"{n / t_japi / 1e6:.1f}", "<= 1.2x kernel",
        f"kernel {n / t_j / 1e6:.1f} M/s", f"{t_japi / t_j:.2f}x")
    return n / t_k


def pinocchio_model(model: zrp.Manipulator):
    """The same arm in Pinocchio: joint k at p_k with axis u_{k,0}, the tool at b_{n+1}."""
    import pinocchio as pin

    pm = pin.Model()
    parent = 0
    for k in range(model.n):
        place = pin.SE3(np.eye(3), np.asarray(model.bodies[k], dtype=float))
        axis = np.asarray(model.axes[k], dtype=float)
        jm = (pin.JointModelPrismaticUnaligned(axis) if model.prismatic[k]
              else pin.JointModelRevoluteUnaligned(axis))
        parent = pm.addJoint(parent, jm, place, f"j{k + 1}")
    tool = pin.SE3(np.eye(3), np.asarray(model.bodies[model.n], dtype=float))
    pm.addFrame(pin.Frame("tool", parent, 0, tool, pin.FrameType.OP_FRAME))
    return pm


def _pinocchio_calls(model: zrp.Manipulator, q: np.ndarray) -> dict:
    """Pinocchio's calls on the same arm (empty where it is not installed): forward
    kinematics alone, with the frame placements (the tool's pose), and the Jacobian. Checked
    against zrp first: the same tool position and rotation."""
    try:
        import pinocchio as pin
    except ImportError:
        return {}
    pm = pinocchio_model(model)
    pd = pm.createData()
    fid = pm.getFrameId("tool")
    pin.forwardKinematics(pm, pd, q)
    pin.updateFramePlacements(pm, pd)
    p, er = zrp.end_effector_pose(model, q)
    assert np.allclose(pd.oMf[fid].translation, p)
    assert np.allclose(pd.oMf[fid].rotation, matrix_from_er(er))

    def fk_frames():
        pin.forwardKinematics(pm, pd, q)
        pin.updateFramePlacements(pm, pd)

    return {"fk": lambda: pin.forwardKinematics(pm, pd, q), "fk_frames": fk_frames,
            "jac": lambda: (pin.computeJointJacobians(pm, pd, q),
                            pin.getJointJacobian(pm, pd, model.n, pin.LOCAL_WORLD_ALIGNED))}


def _mujoco_calls(model: zrp.Manipulator, q: np.ndarray) -> dict:
    """MuJoCo's mj_kinematics and its Jacobian on the equivalent MJCF (empty without it)."""
    try:
        import mujoco

        import mjcf
    except ImportError:
        return {}
    m = mjcf.build(model).model
    d = mujoco.MjData(m)
    d.qpos[:] = q
    jp = np.empty((3, m.nv))
    jr = np.empty((3, m.nv))

    def mj_fk():
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)

    def mj_jac():
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_jacBody(m, d, jp, jr, m.nbody - 1)

    return {"fk": mj_fk, "jac": mj_jac}


def single_calls(model: zrp.Manipulator) -> None:
    """One FK call and one Jacobian through the public API against Pinocchio and MuJoCo on
    the same arm, all timed in turn within each round (CPU time per call)."""
    q = np.array([0.1, -0.4, 0.3, 0.7, 1.2, -0.5])
    pin_calls, mj_calls = _pinocchio_calls(model, q), _mujoco_calls(model, q)
    fns = {"fk": lambda: zrp.end_effector_pose(model, q), "jac": lambda: zrp.jacobian(model, q),
           **{f"pin_{k}": f for k, f in pin_calls.items()},
           **{f"mj_{k}": f for k, f in mj_calls.items()}}
    t = dict(zip(fns, per_call(*fns.values()), strict=True))
    fk, jac = t["fk"], t["jac"]
    print(f"  (single calls: CPU time; wall {fk.wall * 1e6:.2f} us for one FK call; "
          f"load {fk.load[0]:.1f}-{fk.load[1]:.1f})")
    if pin_calls:
        frames, bare, pj = t["pin_fk_frames"], t["pin_fk"], t["pin_jac"]
        row("one FK call, end_effector_pose (us)", _us(fk), "<= 2x Pinocchio",
            f"Pinocchio FK + frames {_us(frames)} us", f"{fk.cpu / frames.cpu:.2f}x Pinocchio")
        row("  the same against forwardKinematics alone", _us(fk), "",
            f"Pinocchio FK {_us(bare)} us", f"{fk.cpu / bare.cpu:.2f}x Pinocchio")
        row("one Jacobian call, jacobian (us)", _us(jac), "<= 2", f"Pinocchio {_us(pj)} us",
            f"{jac.cpu / pj.cpu:.2f}x Pinocchio")
    else:
        row("one FK call, end_effector_pose (us)", _us(fk), "<= 2x Pinocchio",
            "Pinocchio not installed", "")
        row("one Jacobian call, jacobian (us)", _us(jac), "<= 2", "Pinocchio not installed", "")
    if mj_calls:
        row("  MuJoCo mj_kinematics per call (us)", _us(t["mj_fk"]), "",
            f"zrp {_us(fk)} us", f"zrp {fk.cpu / t['mj_fk'].cpu:.2f}x")
        row("  MuJoCo kinematics+comPos+jacBody (us)", _us(t["mj_jac"]), "",
            f"zrp {_us(jac)} us", f"zrp {jac.cpu / t['mj_jac'].cpu:.2f}x")


def monte_carlo(n_robots: int, workers: bool, fk_rate: float) -> None:
    from zrp.manufacturing import Tolerances, monte_carlo_summary
    from zrp.manufacturing import monte_carlo as mc

    setup = zrp.puma_circle()
    res = zrp.track_trajectory(setup.model, setup.trajectory, setup.q0, 359)
    q = res.q  # 360 points
    tol = Tolerances.build(setup.model, length=0.02, angle_rad=5e-5)
    mc(setup.model, q, tol, 512, seed=1)  # warm-up
    t1, t_red = best(lambda: mc(setup.model, q, tol, n_robots, seed=1),
                     lambda: monte_carlo_summary(setup.model, q, tol, n_robots, seed=1),
                     repeat=2)
    rate = n_robots * q.shape[0] / t1
    row(f"Monte Carlo {n_robots:.0e} x {q.shape[0]}, one core (s)", f"{t1:.2f}", "<= 0.7",
        f"FK kernel {fk_rate / 1e6:.1f} M poses/s", f"{rate / 1e6:.1f} M poses/s "
        f"({rate / fk_rate:.2f}x; perturbed arms: no sparse axes)")
    row("  the same reduced on the workers (s)", f"{t_red:.2f}", "", f"gathered {t1:.2f} s",
        f"{t_red / t1:.2f}x")
    t_fo = best(lambda: mc(setup.model, q, tol, n_robots, seed=1, first_order=True), repeat=2)
    row("  with the first-order maxima too, as zrp tolerance (s)", f"{t_fo:.2f}", "",
        f"nonlinear only {t1:.2f} s", f"{t_fo / t1:.2f}x")
    if not workers:
        return
    from zrp.cli.cluster import executor

    times: dict[int, list[float]] = {1: [], 2: []}
    from zrp.manufacturing.chunks import chunk_size

    # chosen from the work (the default): 1e5 x 360 -> 4 tasks of 25,000 robots, 2 + 2 on two
    # workers (the former fixed 4,096: 25 tasks, 13 + 12, and 25 tasks' fixed costs)
    chunk = chunk_size(n_robots, q.shape[0])
    with executor(1) as e1, executor(2) as e2:
        for ex in (e1, e2):
            mc(setup.model, q, tol, 4096, seed=1, chunk=512, executor=ex)  # warm-up
        for _ in range(3):  # interleaved: both see the same load
            for w, ex in ((1, e1), (2, e2)):
                t = time.perf_counter()
                mc(setup.model, q, tol, n_robots, seed=1, chunk=chunk, executor=ex)
                times[w].append(time.perf_counter() - t)
    t1, t2 = min(times[1]), min(times[2])
    row(f"Monte Carlo on a Dask LocalCluster, 2 workers (s; chunk {chunk})", f"{t2:.2f}",
        ">= 1.8x faster", f"1 worker {t1:.2f} s", f"{t1 / t2:.2f}x faster (load "
        f"{os.getloadavg()[0]:.1f})")


def diagnosis() -> None:
    if not (SHARED / "measurements.csv").exists():
        row("diagnosis of the IRB 120 data", "skipped", "<= 3 s", "../shared absent", "")
        return
    import contextlib

    from zrp.blas import blas_threads
    from zrp.gap import diagnose, load_measurements, pipeline
    from zrp.gap.fit import leastsq
    from zrp.gap.fit.leastsq import fit, initial_registration
    from zrp.gap.model.context import Context
    from zrp.gap.model.effects import registration_parameters
    from zrp.gap.model.problem import compressed

    model = zrp.load_model(str(SHARED / "irb120.toml"))
    lines = (SHARED / "measurements.csv").read_text(encoding="utf-8").splitlines()
    with tempfile.TemporaryDirectory() as tmp:
        part = Path(tmp) / "first999.csv"
        part.write_text("\n".join(lines[:1000]) + "\n", encoding="utf-8")
        for label, path, goal in (("2,946 points", SHARED / "measurements.csv", "<= 3 s"),
                                  ("999 points", part, "<= 1 s")):
            meas = load_measurements(path, model, deg=True)
            ctx = Context(model, meas)
            poses = np.arange(len(meas.pose_ids))
            specs = registration_parameters(ctx)

            def registration(ctx=ctx, specs=specs, poses=poses):
                th0, rb0 = initial_registration(ctx, specs, poses)
                return fit(ctx, specs, poses, th0, rb0)

            def tall(model=model, meas=meas):  # the former fit: MINPACK's QR of the tall J
                leastsq.compressed = lambda r, jac: (r, jac)
                try:
                    return diagnose(model, meas, seed=0)
                finally:
                    leastsq.compressed = compressed

            def threaded(model=model, meas=meas):  # the former: OpenBLAS's own threads
                pipeline.blas_threads = lambda _n: contextlib.nullcontext()
                try:
                    return diagnose(model, meas, seed=0)
                finally:
                    pipeline.blas_threads = blas_threads

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t_reg, t_full, t_tall, t_thr = best(
                    registration, lambda model=model, meas=meas: diagnose(model, meas, seed=0),
                    tall, threaded, repeat=3)
            row(f"diagnosis, IRB 120 {label} (s)", f"{t_full:.2f}", goal,
                f"registration {t_reg:.3f} s", f"{t_full / t_reg:.0f}x")
            row("  the same, LM on the tall Jacobian (s)", f"{t_tall:.2f}", "",
                f"QR-compressed {t_full:.2f} s", f"{t_tall / t_full:.2f}x slower")
            row("  the same on OpenBLAS's own threads (s)", f"{t_thr:.2f}", "",
                f"one BLAS thread {t_full:.2f} s", f"{t_thr / t_full:.2f}x slower")


def simulation(poses: int) -> None:
    from sim.robot.effects import default_tool_points, true_geometry
    from sim.studies.benchmark import BenchmarkConfig, draw_scenarios, simulate_scenario
    from zrp.kinematics import reachable_poses

    model = zrp.load_model("puma")
    cfg = BenchmarkConfig(scenarios=3, seed=0, poses=poses, none_fraction=0.0,
                          pair_fraction=0.0)
    scns = draw_scenarios(model, cfg)
    tool = default_tool_points(model)
    import functools

    import sim.studies.benchmark.blind as blind
    from sim.robot.measurement import Procedure

    with tempfile.TemporaryDirectory() as tmp:
        times = [simulate_scenario(model, s, cfg, Path(tmp), Path(tmp))[2] for s in scns]
        try:  # the former procedure, every move to a pre-pose stepped through (same run)
            blind.Procedure = functools.partial(Procedure, transfer="simulate")
            t_old = [simulate_scenario(model, s, cfg, Path(tmp), Path(tmp))[2] for s in scns]
        finally:
            blind.Procedure = Procedure
    t0 = time.perf_counter()
    for s in scns:
        q = reachable_poses(model, poses, np.random.default_rng(s.seed))
        fk = zrp.forward_kinematics(true_geometry(model, s.effects), q)
        _ = fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, tool)
    t_kin = (time.perf_counter() - t0) / len(scns)
    row(f"blind-benchmark simulation, {poses} poses (s)", f"{np.median(times):.2f}",
        "<= 1 s", f"kinematics only {t_kin * 1e3:.1f} ms", f"{np.median(times) / t_kin:.0f}x")
    row("  the same, moves to pre-poses simulated (s)", f"{np.median(t_old):.2f}", "",
        f"jumped {np.median(times):.2f} s", f"{np.median(t_old) / np.median(times):.2f}x slower")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes, no cluster")
    ap.add_argument("--only", choices=("diagnosis", "single"), help="only this figure "
                    "(single: one FK call and one Jacobian against Pinocchio and MuJoCo)")
    add_output_arguments(ap, "bench_speed")
    args = ap.parse_args()
    if args.only:
        args.report_name = f"bench_speed_{args.only}"
    out = output_path(args)
    print(f"issue-15 speed figures (one core for the kernels; load {os.getloadavg()[0]:.1f})")
    if args.only == "diagnosis":
        diagnosis()
    elif args.only == "single":
        single_calls(zrp.load_model("puma"))
    else:
        model = zrp.load_model("puma")
        fk_rate = batched(model, 200_000 if args.quick else 1_000_000)
        single_calls(model)
        monte_carlo(10_000 if args.quick else 100_000, workers=not args.quick, fk_rate=fk_rate)
        diagnosis()
        simulation(50 if args.quick else 200)
    print(f"(load average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    report = Report(args.report_name, "the issue-15 speed figures, each beside a baseline "
                    "measured in the same run")
    report.table("Kernels on one core (NUMBA_NUM_THREADS=1); best of interleaved repeats",
                 ["figure", "measured", "target", "baseline (same run)", "ratio"],
                 [(("... " + r[0].strip()) if r[0].startswith(" ") else r[0], *r[1:])
                  for r in ROWS])
    report.write(out, args)


if __name__ == "__main__":
    main()
