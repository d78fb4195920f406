"""Benchmark of the command line's start-up: ``zrp --help`` and ``zrp <cmd> --help``.

Goal (issue 23): under 0.3 s on a quiet machine (it was 1.3 s, ``import zrp`` 1.1 s). Each
timing is a plain subprocess (a fresh interpreter, as a user's shell starts it), the best of
``--repeat`` runs, printed beside ``python -c pass`` and ``python -c "import numpy"`` measured in
the same run, so the ratios stay meaningful on a loaded machine: on an idle one ``python -c
pass`` takes about 0.02-0.1 s. The modules a command imports only when it runs (SciPy,
numba, MuJoCo, Matplotlib, Dask) are checked, not timed, by tests/cli/test_startup.py.

Run: python3 tests/benchmarks/bench_cli_startup.py [--repeat N] [--quick] [--out FILE.md]
[--force] (writes renders/benchmarks/bench_cli_startup.md and .json; --quick: 3 repeats).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

from _report import Report, add_output_arguments, output_path

ROOT = Path(__file__).resolve().parents[2]
GOAL_S = 0.3
COMMANDS = ("diagnose", "calibrate", "tolerance", "paper", "render", "ik")


def best_of(argv: list[str], repeat: int) -> float:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(argv, env=env, check=True, stdout=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=10, help="runs of each, best kept")
    ap.add_argument("--quick", action="store_true", help="3 repeats")
    add_output_arguments(ap, "bench_cli_startup")
    args = ap.parse_args()
    out = output_path(args)
    repeat = 3 if args.quick else max(1, args.repeat)
    py = sys.executable
    base = best_of([py, "-c", "pass"], repeat)
    numpy = best_of([py, "-c", "import numpy"], repeat)
    rows = [["python -c pass", f"{base:.3f}", "1.00", ""],
            ["python -c 'import numpy'", f"{numpy:.3f}", f"{numpy / base:.2f}", ""]]
    cases = [("import zrp", [py, "-c", "import zrp"]),
             ("zrp --help", [py, "-m", "zrp", "--help"])]
    cases += [(f"zrp {c} --help", [py, "-m", "zrp", c, "--help"]) for c in COMMANDS]
    for label, argv in cases:
        t = best_of(argv, repeat)
        rows.append([label, f"{t:.3f}", f"{t / base:.2f}",
                     "yes" if t <= GOAL_S else f"no (goal {GOAL_S} s)"])
        print(f"{label:28s} {t:.3f} s  x{t / base:.2f} of python -c pass", flush=True)
    report = Report("bench_cli_startup", "Start-up of the command line")
    report.table(f"Start-up (best of {repeat} fresh processes)",
                 ["command", "time (s)", "/ python -c pass", f"<= {GOAL_S} s"], rows,
                 note="A fresh interpreter each; the ratio to `python -c pass` in the same run "
                      "is the figure to compare across machines and loads.")
    report.write(out, args)


if __name__ == "__main__":
    main()
