"""Timing and accuracy of the blind gap benchmark: 50 single-effect scenarios of 200 poses.

Target: the whole run (MuJoCo simulation of every measurement session, blind diagnosis,
scoring) within 10 minutes on this machine, with a progress bar. Baselines measured in the
same run: the same poses "measured" kinematically (forward kinematics of the true geometry, no
dynamics) and real time (how long the simulated sessions would take on the robot).

    python3 tests/benchmarks/bench_gap_benchmark.py [--scenarios 50] [--poses 200] [--seed 0]

Writes the tables to renders/gap_benchmark_bench/ (generated output, replaced).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import zrp
from sim.studies.benchmark import (
    BenchmarkConfig,
    draw_scenarios,
    render_text,
    run_benchmark,
    write_outputs,
)
from zrp.cli.cluster import executor

ROOT = Path(__file__).resolve().parents[1]
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
    ap.add_argument("--out", default=str(ROOT / "renders" / "gap_benchmark_bench"))
    args = ap.parse_args()
    model = zrp.load_model("puma")
    cfg = BenchmarkConfig(scenarios=args.scenarios, seed=args.seed, poses=args.poses,
                          none_fraction=0.0, pair_fraction=0.0)
    out = Path(args.out)
    base = kinematic_baseline(model, cfg)
    t0 = time.perf_counter()
    with executor(args.workers) as ex:
        t0 = time.perf_counter()  # the cluster's start-up is not the benchmark's
        res = run_benchmark(model, cfg, out / "work", progress=True, executor=ex)
        wall = time.perf_counter() - t0
    write_outputs(res, out, overwrite=True)
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


if __name__ == "__main__":
    main()
