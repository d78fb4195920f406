"""Benchmark: how the cost of hostile-size inputs grows (issue 26). Not a timed test: it
prints figures and ratios measured in the same run.

* ``zrp diagnose-motion`` on trajectory CSVs of N rows (PUMA, 1 kHz, joints moving on sums of
  sines, a hidden 4 ms sync delay, 0.02 mm noise): wall time, CPU time and peak memory of the
  whole command in a fresh process (reading, the diagnosis, writing). The ratio of CPU time
  per row to the smallest file's says whether the cost is linear in the rows (about 1) or
  worse. Before issue 26: 1e6 rows took 434 s and 5.3 GB.
* URDF import (``zrp.import_urdf``) of chains of 5,000 and 20,000 joints (CPU time; a ratio of
  about 4 is linear: it was quadratic, 109 s for 20,000 joints) and of a 20 MB file that is
  mostly comments (it took 46 s).

Run from the repository root: PYTHONPATH=. python3 tests/benchmarks/bench_input_scaling.py
[--quick] [--out FILE.md] [--force] (--quick: 1e5 rows at most). Writes the tables to
renders/benchmarks/bench_input_scaling.md and .json.
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
from zrp.gap.motion import Trajectory, write_trajectory
from zrp.model.urdf import import_urdf

ROOT = Path(__file__).resolve().parents[2]


def _trajectory_csv(rows: int, folder: Path) -> Path:
    """A 1 kHz trajectory of ``rows`` samples with a hidden 4 ms sync delay."""
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    t = np.arange(rows) / 1000.0
    q0 = np.radians([0, -20, 30, 0, 60, 0])
    f, a, ph = (rng.uniform(lo, hi, (3, 6)) for lo, hi in ((0.05, 0.4), (0.2, 0.6), (0, 6)))

    def q_at(tt: np.ndarray) -> np.ndarray:
        return q0 + (a * np.sin(2 * np.pi * f * tt[:, None, None] + ph)).sum(axis=1)

    xyz = zrp.forward_kinematics(model, q_at(t - 0.004)).position
    xyz = xyz + rng.normal(0.0, 0.02, xyz.shape)
    return write_trajectory(Trajectory(t, q_at(t), xyz, ("p1",), "base"),
                            folder / f"t{rows}.csv")


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _diagnose_motion(path: Path, out: Path) -> tuple[float, float, float, str]:
    """Wall time (s), CPU time (s), peak resident memory (MB) and the verdict's first line of
    `zrp diagnose-motion` in a fresh process."""
    code = ("import resource, sys; from zrp.cli import main; rc = main(sys.argv[1:]); "
            "print('PEAK_MB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); "
            "sys.exit(rc)")
    t0, c0 = time.perf_counter(), _cpu_children()
    proc = subprocess.run([sys.executable, "-c", code, "diagnose-motion", "--model", "puma",
                           "--data", str(path), "--frame", "base", "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True, check=False)
    wall, cpu = time.perf_counter() - t0, _cpu_children() - c0
    if proc.returncode != 0:
        raise SystemExit(proc.stderr)
    peak = float(proc.stdout.rsplit("PEAK_MB", 1)[1].split()[0])
    return wall, cpu, peak, proc.stdout.splitlines()[0][:100]


def _urdf(n: int, comment: int = 0) -> str:
    out = ['<robot name="chain">', '<link name="l0"/>']
    for k in range(1, n + 1):
        out.append(f'<link name="l{k}"/>')
        if comment:
            out.append("<!-- " + "c" * comment + " -->")
        out.append(f'<joint name="j{k}" type="revolute"><parent link="l{k - 1}"/>'
                   f'<child link="l{k}"/><origin xyz="0 0 0.1" rpy="0 0 0"/>'
                   '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1"/></joint>')
    return "\n".join([*out, "</robot>"])


def _cpu(fn, *args) -> float:
    best = float("inf")
    for _ in range(2):  # best of two, CPU time: the machine is shared
        t0 = time.process_time()
        fn(*args)
        best = min(best, time.process_time() - t0)
    return best


def _urdf_rows(folder: Path) -> list[tuple[str, ...]]:
    rows, base = [], None
    for n in (5000, 20000):
        path = folder / f"c{n}.urdf"
        path.write_text(_urdf(n))
        cpu = _cpu(import_urdf, path)
        base = base or cpu
        rows.append((f"{n:,} joints", f"{path.stat().st_size / 1e6:.1f}", f"{cpu:.2f}",
                     f"{cpu / base:.2f}" + (" (linear: about 4)" if n == 20000 else "")))
    path = folder / "comments.urdf"
    path.write_text(_urdf(2000, comment=10000))
    cpu = _cpu(import_urdf, path)
    rows.append(("2,000 joints, mostly comments", f"{path.stat().st_size / 1e6:.1f}",
                 f"{cpu:.2f}", "(was 46 s)"))
    for r in rows:
        print("URDF " + ", ".join(r))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e5 rows at most")
    add_output_arguments(ap, "bench_input_scaling")
    args = ap.parse_args()
    out = output_path(args)
    report = Report("bench_input_scaling", "the cost of large trajectory and URDF inputs")
    sizes = [25_000, 100_000] + ([] if args.quick else [400_000, 1_000_000])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        report.table("URDF import (CPU time, best of 2)",
                     ["file", "MB", "CPU s", "ratio to 5,000 joints"], _urdf_rows(folder))
        base = None
        for n in sizes:
            path = _trajectory_csv(n, folder)
            wall, cpu, peak, verdict = _diagnose_motion(path, folder / f"out{n}")
            per_row = cpu / n
            base = base or per_row
            print(f"{n:>10,} rows: wall {wall:.1f} s, CPU {cpu:.1f} s, peak {peak:.0f} MB, "
                  f"CPU per row x {per_row / base:.2f} of {sizes[0]:,} rows; {verdict}")
            rows.append((f"{n:,}", f"{wall:.1f}", f"{cpu:.1f}", f"{peak:.0f}",
                         f"{peak * 1024 / n:.1f}", f"{per_row / base:.2f}", verdict))
            os.remove(path)
    report.table("`zrp diagnose-motion` in a fresh process on N rows (PUMA, 1 kHz, hidden "
                 "4 ms sync delay, 0.02 mm noise; before issue 26: 1e6 rows 434 s, 5.3 GB)",
                 ["rows", "wall s", "CPU s", "peak MB", "peak KB per row",
                  f"CPU per row / {sizes[0]:,} rows'", "verdict"], rows)
    report.write(out, args)


if __name__ == "__main__":
    main()
