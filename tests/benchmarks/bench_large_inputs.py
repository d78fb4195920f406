"""Benchmark: large inputs (issue 13). Not a timed test: it prints figures and ratios.

* ``zrp diagnose`` on measurement files of 1e5 and 1e6 rows (PUMA, 3 reflectors per pose,
  one hidden joint offset, 0.02 mm noise): wall time and peak memory of the whole command
  (reading, the announced subsample of ``--max-points``, the diagnosis, writing). Goals: 1e5
  rows within 60 s, 1e6 rows within 10 minutes and 2 GB. The baseline measured in the same
  run is the 1e3-row file through the same command, so the ratios (of CPU time) say how the
  cost grows.
* The model-file parser on 1,000 and 4,000 joints: the ratio of the times is about 4 when
  the parser is linear (it was quadratic: 66 s for 4,000 joints).

Run from the repository root: PYTHONPATH=. python3 tests/benchmarks/bench_large_inputs.py
[--quick] [--out FILE.md] [--force] (--quick: 1e5 rows at most; without PYTHONPATH=. a script
in tests/benchmarks imports whichever zrp is installed, not the checkout's). Writes the tables
to renders/benchmarks/bench_large_inputs.md and .json.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _report import Report, add_output_arguments, output_path

import zrp
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.model.files import dumps_model, loads_model

ROOT = Path(__file__).resolve().parents[2]
GOALS = {100_000: (60.0, None), 1_000_000: (600.0, 2048.0)}  # s, MB
TOOLS = ((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -50.0, 30.0))


def _csv(rows: int, folder: Path) -> Path:
    model = zrp.load_model("puma")
    rng = np.random.default_rng(rows)
    poses = -(-rows // len(TOOLS))
    meas = synthesize(model, uniform_joint_values(model, poses, rng),
                      Injection(joint_offset={2: 1e-3}), rng=rng, noise_sigma=0.02,
                      tool_offsets=TOOLS)
    return meas.to_csv(folder / f"d{rows}.csv")


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _diagnose(path: Path, out: Path) -> tuple[float, float, float, str]:
    """Wall time (s), CPU time (s) and peak resident memory (MB) of `zrp diagnose` in a fresh
    process (CPU time is what a loaded, shared machine does not inflate)."""
    code = ("import resource, sys; from zrp.cli import main; rc = main(sys.argv[1:]); "
            "print('PEAK_MB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); "
            "sys.exit(rc)")
    t0, c0 = time.perf_counter(), _cpu_children()
    proc = subprocess.run([sys.executable, "-c", code, "diagnose", "--model", "puma", "--data",
                           str(path), "--no-plots", "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    wall, cpu = time.perf_counter() - t0, _cpu_children() - c0
    if proc.returncode != 0:
        raise SystemExit(proc.stderr)
    peak = float(proc.stdout.rsplit("PEAK_MB", 1)[1].split()[0])
    note = next((ln for ln in proc.stderr.splitlines() if "exceed max_points" in ln), "")
    return wall, cpu, peak, note


def _parser_ratio() -> tuple[float, float]:
    text = dumps_model(zrp.load_model("puma"))
    head, rest = text.split("[[joint]]", 1)
    joint = "[[joint]]" + rest.split("[[joint]]")[0].split("[end_effector]")[0]
    ee = "[end_effector]" + text.split("[end_effector]")[1]
    times = []
    for n in (1000, 4000):
        text_n = head + joint * n + ee
        best = float("inf")
        for _ in range(3):  # best of three, CPU time: the machine is shared
            t0 = time.process_time()
            loads_model(text_n)
            best = min(best, time.process_time() - t0)
        times.append(best)
    return times[0], times[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e5 rows at most")
    add_output_arguments(ap, "bench_large_inputs")
    args = ap.parse_args()
    out = output_path(args)
    report = Report("bench_large_inputs", "large measurement files and model files")
    t1k, t4k = _parser_ratio()
    print(f"model file (CPU time): 1,000 joints {t1k:.3f} s, 4,000 joints {t4k:.3f} s, ratio "
          f"{t4k / t1k:.2f} (linear: about 4)")
    report.table("The model-file parser (CPU time, best of 3)", ["joints", "CPU s", "ratio"],
                 [("1,000", f"{t1k:.3f}", ""),
                  ("4,000", f"{t4k:.3f}", f"{t4k / t1k:.2f} x 1,000 joints (linear: about 4)")])
    rows, notes = [], []
    sizes = [1_000, 100_000] + ([] if args.quick else [1_000_000])
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        base = None
        print(f"{'rows':>10}{'wall s':>9}{'CPU s':>9}{'peak MB':>9}{'x 1e3 rows':>12}"
              f"{'goal':>22}")
        for rows_n in sizes:
            path = _csv(rows_n, folder)
            wall, cpu, peak, note = _diagnose(path, folder / f"out{rows_n}")
            base = base or cpu
            goal_s, goal_mb = GOALS.get(rows_n, (None, None))
            goal = "" if goal_s is None else f"<= {goal_s:g} s" + (
                f", {goal_mb:g} MB" if goal_mb else "")
            print(f"{rows_n:>10,}{wall:>9.1f}{cpu:>9.1f}{peak:>9.0f}{cpu / base:>12.2f}"
                  f"{goal:>22}")
            rows.append((f"{rows_n:,}", f"{wall:.1f}", f"{cpu:.1f}", f"{peak:.0f}",
                         f"{cpu / base:.2f}", goal))
            if note:
                notes.append(f"{rows_n:,} rows: " + note.split("DataWarning: ", 1)[-1][:300])
                print("           " + note.split("DataWarning: ", 1)[-1][:160] + " ...")
            os.remove(path)
    report.table("`zrp diagnose` in a fresh process on files of N rows (PUMA, 3 reflectors, "
                 "one hidden joint offset, 0.02 mm noise)",
                 ["rows", "wall s", "CPU s", "peak MB", "CPU x 1e3 rows", "goal"], rows,
                 note="\n\n".join(notes))
    report.write(out, args)


if __name__ == "__main__":
    main()
