"""The blind gap benchmark's remainder scenarios (issue 36): effects the library lacks (gear
errors at the 3rd and 4th harmonic), effect-free and scatter-only, each simulated on the MuJoCo
robot, diagnosed blind with the learned residual term and scored against the truth afterwards
(sim/studies/benchmark/remainder.py), at two pose counts.

    python3 tests/benchmarks/bench_gap_remainder.py [--poses 800 1600] [--quick]
        [--out FILE.md] [--force]

Writes renders/benchmarks/bench_gap_remainder.md (and .json): generated output, replaced.
The 50-scenario run of bench_gap_benchmark.py is separate (10 minutes on a free machine).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _report import Report, add_output_arguments, output_path

import zrp
from sim.studies.benchmark.remainder import (
    WITHIN_NOISE,
    remainder_table,
    run_remainder_benchmark,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, nargs="+", default=[800, 1600])
    ap.add_argument("--quick", action="store_true",
                    help="one size only (800 poses per scenario): a smoke run")
    add_output_arguments(ap, "bench_gap_remainder")
    args = ap.parse_args()
    out_md = output_path(args)
    model = zrp.load_model("puma")
    report = Report("bench_gap_remainder", "what remains: the blind remainder scenarios")
    for poses in [800] if args.quick else args.poses:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as work:
            scores = run_remainder_benchmark(model, Path(work), poses=poses)
        wall = time.perf_counter() - t0
        head, rows = remainder_table(scores, model.length_unit)
        passed = sum(s.passed for s in scores)
        print(f"{poses} poses: {passed}/{len(scores)} pass ({wall:.0f} s)")
        for r in rows:
            print("  " + " | ".join(map(str, r)))
        report.table(
            f"PUMA 560, {poses} poses per scenario (3/4 fitting, 1/4 withheld): {passed} of "
            f"{len(scores)} pass, {wall:.0f} s", head, rows,
            note=(f"Pass: a lacking effect gives structure, its joints named, the learned term "
                  f"kept with a withheld RMS <= {WITHIN_NOISE:g} x the noise RMS sqrt(3) sigma; "
                  "effect-free and scatter-only give no structure and no term. 'structure "
                  "recovered': the share of the withheld mean square above the noise that the "
                  "learned term removes."))
    report.write(out_md, args)


if __name__ == "__main__":
    main()
