"""Timing and accuracy of the blind gap benchmark: 50 single-effect scenarios of 200 poses.

Target: the whole run (MuJoCo simulation of every measurement session, blind diagnosis,
scoring) within 10 minutes on this machine, with a progress bar. Baselines measured in the
same run: the same poses "measured" kinematically (forward kinematics of the true geometry, no
dynamics) and real time (how long the simulated sessions would take on the robot).

    python3 tests/benchmarks/bench_gap_benchmark.py [--scenarios 50] [--poses 200] [--seed 0]
        [--workers N] [--quick] [--out FILE.md] [--force]

Writes the timing table to renders/benchmarks/bench_gap_benchmark.md (and .json) and the
benchmark's own tables (summary.md, confusion.csv, scenarios.csv, results.json, confusion.png)
into the folder of the same name beside it (generated output, replaced; an --out elsewhere
needs --force to replace). --quick: 4 scenarios of 50 poses.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _report import Report, add_output_arguments, check_outputs, output_path

import zrp
from sim.studies.benchmark import (
    BenchmarkConfig,
    draw_scenarios,
    render_text,
    run_benchmark,
    write_outputs,
)
from zrp.cli.cluster import executor

TARGET_S = 600.0


def kinematic_baseline(model: zrp.Manipulator, cfg: BenchmarkConfig) -> float:
    """Seconds to compute the same sessions' tool points by forward kinematics only."""
    from sim.robot.effects import default_tool_points, true_geometry
    from zrp.kinematics import reachable_poses

    tool = default_tool_points(model)
    t0 = time.perf_counter()
    for scn in draw_scenarios(model, cfg):
        q = reachable_poses(model, cfg.poses, np.random.default_rng(scn.seed))
        fk = zrp.forward_kinematics(true_geometry(model, scn.effects), q)
        _ = fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, tool)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", type=int, default=50)
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=None,
                    help="Dask local cluster of N worker processes (default: this process)")
    ap.add_argument("--quick", action="store_true", help="4 scenarios of 50 poses")
    add_output_arguments(ap, "bench_gap_benchmark")
    args = ap.parse_args()
    out_md = output_path(args)
    out = out_md.with_suffix("")  # the benchmark's own tables, in a folder beside the report
    check_outputs(args, [out / "summary.md"])
    if args.quick:
        args.scenarios, args.poses = min(args.scenarios, 4), min(args.poses, 50)
    model = zrp.load_model("puma")
    cfg = BenchmarkConfig(scenarios=args.scenarios, seed=args.seed, poses=args.poses,
                          none_fraction=0.0, pair_fraction=0.0)
    base = kinematic_baseline(model, cfg)
    t0 = time.perf_counter()
    with executor(args.workers) as ex:
        t0 = time.perf_counter()  # the cluster's start-up is not the benchmark's
        res = run_benchmark(model, cfg, out / "work", progress=True, executor=ex)
        wall = time.perf_counter() - t0
    write_outputs(res, out, overwrite=args.replace)
    print(render_text(res))
    # real time of the sessions: the t column of each CSV's last pose (motion, settling and
    # 5 s per tracker reading)
    simulated = 0.0
    for f in sorted((out / "work" / "measurements").glob("*.csv")):
        lines = f.read_text().strip().splitlines()
        simulated += float(lines[-1].split(",")[lines[0].split(",").index("t")])
    n = len(res.scores)
    print(f"{n} scenarios x {args.poses} poses, {args.workers or 1} process(es): wall {wall:.1f} s "
          f"(target <= {TARGET_S:.0f} s: {'met' if wall <= TARGET_S else 'MISSED'}), "
          f"{wall / n:.2f} s per scenario")
    print(f"  summed over processes: simulation {res.sim_s:.1f} s ({res.sim_s / n:.2f} s per "
          f"session), diagnosis {res.diag_s:.1f} s ({res.diag_s / n:.2f} s per run)")
    print(f"  baseline, kinematic measurement of the same poses (no dynamics): {base:.2f} s "
          f"-> physics costs {res.sim_s / max(base, 1e-9):.0f}x the kinematics")
    print(f"  baseline, real time of the measured sessions (incl. 5 s per tracker reading): "
          f"{simulated / 3600:.1f} h -> simulation {simulated / max(res.sim_s, 1e-9):.0f}x "
          f"faster than real time")
    print(f"wrote {out}/summary.md, confusion.csv, scenarios.csv, results.json, confusion.png")
    target = f"<= {TARGET_S:.0f} s: {'met' if wall <= TARGET_S else 'MISSED'}"
    report = Report("bench_gap_benchmark", "the blind gap benchmark's time and scores")
    report.table(
        f"{n} single-effect scenarios x {args.poses} poses (seed {args.seed}), "
        f"{args.workers or 1} process(es)", ["figure", "measured", "target / baseline"],
        [("wall time", f"{wall:.1f} s ({wall / n:.2f} s per scenario)", target),
         ("simulation, summed over processes", f"{res.sim_s:.1f} s ({res.sim_s / n:.2f} s "
          "per session)", f"kinematic measurement of the same poses {base:.2f} s: physics "
          f"{res.sim_s / max(base, 1e-9):.0f}x"),
         ("diagnosis, summed over processes", f"{res.diag_s:.1f} s "
          f"({res.diag_s / n:.2f} s per run)", ""),
         ("real time of the simulated sessions (incl. 5 s per tracker reading)",
          f"{simulated / 3600:.1f} h", f"simulation {simulated / max(res.sim_s, 1e-9):.0f}x "
          "faster than real time")],
        note=f"Scores, confusion matrix and failures: [{out.name}/summary.md]"
             f"({out.name}/summary.md) (written by the same run).")
    report.write(out_md, args)


if __name__ == "__main__":
    main()
