"""Benchmark: batched forward kinematics and Jacobians on one and on two cores, against a
MuJoCo ``mj_kinematics`` loop and Pinocchio (one call, and its loop over a batch).

On N random PUMA poses (1e6; --quick 1e5) the calls below are timed in turn within each round
(interleaved, ``_timing.interleaved``: the best of the rounds; CPU time of this process, all
threads, the wall time and the 1-minute load average beside it):

* five batches in a row of ``zrp.end_effector_pose(model, q, threads=1)`` and
  ``threads=2`` (zrp/kinematics/parallel.py: the batch cut in two, each half run by the
  same compiled kernel in its own thread; the result is the one-thread result to the bit),
  and the same for ``zrp.jacobian``;
* a Python loop of MuJoCo's ``mj_kinematics`` on the equivalent MJCF, and of Pinocchio's
  ``forwardKinematics`` + ``updateFramePlacements`` on the equivalent model (Pinocchio has no
  batched forward kinematics; the loop is how a batch is computed with it), both on a subset of
  the poses and scaled;
* one call of each from Python (one pose), per call.

What the second core buys shows in the wall time, not in the CPU time (the same work, cut in
two); it needs a second core that nobody else is using: the load average says how busy the
machine was. The two-core rows print the wall-time gain as it was measured.

Run: python3 tests/benchmarks/bench_fk_cores.py [--quick] [--out FILE.md] [--force]
(writes renders/benchmarks/bench_fk_cores.md and .json).
"""

from __future__ import annotations

import argparse
import sys
import timeit
import warnings
from pathlib import Path

import numpy as np

# measure the checkout this script is in, not whichever copy is installed
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from _report import Report, add_output_arguments, output_path
from _timing import Timing, interleaved

import zrp
from zrp.kinematics.parallel import usable_cores

#: batches computed one after the other per timed call (a batch loop: a second core that was
#: idle takes a while to wake on a shared virtual machine, and one batch is over in ~15 ms)
BATCHES = 5


def _mujoco_loop(model: zrp.Manipulator, q: np.ndarray):
    import mujoco

    import mjcf

    m = mjcf.build(model).model
    d = mujoco.MjData(m)

    def run() -> None:
        for qi in q:
            d.qpos[:] = qi
            mujoco.mj_kinematics(m, d)

    return run


def _pinocchio(model: zrp.Manipulator):
    """The same arm in Pinocchio (joint k at p_k with axis u_{k,0}, the tool at b_{n+1}): its
    model, data and tool frame, checked against zrp's FK."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
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
    fid = pm.addFrame(pin.Frame("tool", parent, 0, tool, pin.FrameType.OP_FRAME))
    pd = pm.createData()
    q = np.array([0.1, -0.4, 0.3, 0.7, 1.2, -0.5])
    pin.framesForwardKinematics(pm, pd, q)
    if not np.allclose(pd.oMf[fid].translation, zrp.end_effector_pose(model, q)[0]):
        raise SystemExit("the Pinocchio model does not give zrp's forward kinematics")
    return pin, pm, pd, fid


def _pin_loop(pin, pm, pd, q: np.ndarray):
    def run() -> None:
        for qi in q:
            pin.forwardKinematics(pm, pd, qi)
            pin.updateFramePlacements(pm, pd)

    return run


def _rate(t: Timing, count: int) -> tuple[str, str]:
    return f"{count / t.cpu / 1e6:.2f}", f"{count / t.wall / 1e6:.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e5 poses instead of 1e6")
    ap.add_argument("--repeat", type=int, default=7, help="interleaved rounds (default 7)")
    add_output_arguments(ap, "bench_fk_cores")
    args = ap.parse_args()
    out = output_path(args)
    model = zrp.load_model("puma")
    n = 100_000 if args.quick else 1_000_000
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, model.n))
    n_loop = 20_000
    pin, pm, pd, _ = _pinocchio(model)
    cores = usable_cores()
    two = min(2, cores)
    held: dict[str, object] = {}

    def fk(threads: int):
        def run() -> None:  # the usual loop: the previous result held while the next is made
            for _ in range(BATCHES):
                held[f"fk{threads}"] = zrp.end_effector_pose(model, q, threads=threads)
        return run

    def jac(threads: int):
        def run() -> None:
            for _ in range(BATCHES):
                held[f"jac{threads}"] = zrp.jacobian(model, q, threads=threads)
        return run

    print(f"PUMA, N = {n:,} poses; {cores} usable cores")
    fk1, fk2, mj, pl = interleaved(fk(1), fk(two), _mujoco_loop(model, q[:n_loop]),
                                   _pin_loop(pin, pm, pd, q[:n_loop]), repeat=args.repeat)
    j1, j2 = interleaved(jac(1), jac(two), repeat=max(3, args.repeat // 2))
    same = (np.array_equal(zrp.end_effector_pose(model, q, threads=1)[0],
                           zrp.end_effector_pose(model, q, threads=two)[0]))
    one = np.array([0.1, -0.4, 0.3, 0.7, 1.2, -0.5])
    calls = 20_000
    single = interleaved(lambda: timeit.timeit(lambda: zrp.end_effector_pose(model, one),
                                               number=calls),
                         lambda: timeit.timeit(lambda: pin.framesForwardKinematics(pm, pd, one),
                                               number=calls),
                         lambda: timeit.timeit(lambda: pin.forwardKinematics(pm, pd, one),
                                               number=calls), repeat=args.repeat)
    mj_rate = n_loop / mj.cpu
    pin_rate = n_loop / pl.cpu
    rows = []

    def add(what: str, t: Timing, count: int, vs_one: Timing | None = None) -> None:
        cpu_rate, wall_rate = _rate(t, count)
        gain = "-" if vs_one is None else f"{vs_one.wall / t.wall:.2f}x wall, " \
                                           f"{t.cpu / vs_one.cpu:.2f}x CPU"
        rows.append([what, cpu_rate, wall_rate, f"{count / t.cpu / mj_rate:.1f}x",
                     f"{count / t.cpu / pin_rate:.1f}x", gain,
                     f"{t.load[0]:.1f}-{t.load[1]:.1f}"])
        print(" | ".join(rows[-1]), flush=True)

    add("zrp end_effector_pose, 1 thread", fk1, BATCHES * n)
    add(f"zrp end_effector_pose, {two} threads", fk2, BATCHES * n, fk1)
    add("zrp jacobian, 1 thread", j1, BATCHES * n)
    add(f"zrp jacobian, {two} threads", j2, BATCHES * n, j1)
    add("MuJoCo mj_kinematics, Python loop", mj, n_loop)
    add("Pinocchio forwardKinematics + frames, Python loop", pl, n_loop)
    per = [f"{t.cpu / calls * 1e6:.2f}" for t in single]
    single_rows = [["zrp end_effector_pose (one pose)", per[0], "-"],
                   ["Pinocchio framesForwardKinematics", per[1],
                    f"zrp {single[0].cpu / single[1].cpu:.2f}x"],
                   ["Pinocchio forwardKinematics (joints only, no frame)", per[2],
                    f"zrp {single[0].cpu / single[2].cpu:.2f}x"]]
    for r in single_rows:
        print(" | ".join(r))
    report = Report("bench_fk_cores", "batched forward kinematics on one and two cores "
                                      "against MuJoCo and Pinocchio")
    report.table(f"PUMA, {n:,} random poses ({cores} usable cores; best of interleaved rounds); "
                 f"{two}-thread result identical to 1 thread: {same}",
                 ["call", "M poses/s (CPU)", "M poses/s (wall)", "vs MuJoCo loop (CPU)",
                  "vs Pinocchio loop (CPU)", "gain over 1 thread", "load"], rows,
                 note=f"Each timed call: {BATCHES} batches one after the other. CPU: process "
                      "time of the call, all threads (a split costs no CPU time: the same "
                      "work); wall: elapsed time, where a free second core shows. "
                      f"The loops run on {n_loop:,} of the poses. Load: 1-minute load average "
                      "at the start and end of the rounds (2 cores).")
    report.table(f"One call from Python (CPU us per call, best of {args.repeat} rounds of "
                 f"{calls:,} calls)", ["call", "us per call (CPU)", "ratio"], single_rows)
    report.write(out, args)


if __name__ == "__main__":
    main()
