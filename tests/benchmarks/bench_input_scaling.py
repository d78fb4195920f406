"""Benchmark: how the cost of hostile-size inputs grows (issue 26). Not a timed test: it
prints figures and ratios measured in the same run.

* ``zrp diagnose-motion`` on trajectory CSVs of N rows (PUMA, 1 kHz, joints moving on sums of
  sines, a hidden 4 ms sync delay, 0.02 mm noise): wall time, CPU time and peak memory of the
  whole command in a fresh process (reading, the diagnosis, writing). The ratio of CPU time
  per row to the smallest file's says whether the cost is linear in the rows (about 1) or
  worse. Before issue 26: 1e6 rows took 434 s and 5.3 GB.
* URDF import (``zrp.import_urdf``) of chains of 5,000 and 20,000 joints (CPU time; a ratio of
  about 4 is linear: it was quadratic, 109 s for 20,000 joints) and of a 20 MB file that is
  mostly comments (it took 46 s), and of files of 4e5 and 9e5 short comments on lines of their
  own (a ratio of about 2.25 is linear; 2e6 took 50 s, quadratic, and is now refused by
  ``zrp.xmlio.MAX_XML_MARKUP``).

* With ``--baseline REF``: each trajectory file also runs through the code of git commit REF
  (extracted by ``git archive`` into a temporary folder) in the same run, and the table gives
  the ratios of peak memory and wall time of this checkout to that baseline (e.g. the memory
  work on ``diagnose-motion`` against the commit before it). ``--rows`` picks the sizes (e.g.
  ``--rows 200000 --baseline main --skip-urdf``: 2e5 rows show the peak; it grows linearly).

Run from the repository root: PYTHONPATH=. python3 tests/benchmarks/bench_input_scaling.py
[--quick] [--rows N ...] [--baseline REF] [--skip-urdf] [--out FILE.md] [--force] (--quick:
1e5 rows at most). Writes the tables to renders/benchmarks/bench_input_scaling.md and .json.
"""

from __future__ import annotations

import argparse
import io
import os
import resource
import subprocess
import sys
import tarfile
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


def _checkout(ref: str, folder: Path) -> Path:
    """The code of git commit ``ref`` extracted into ``folder`` (``git archive``)."""
    tar = subprocess.run(["git", "archive", "--format=tar", ref], cwd=ROOT,
                         capture_output=True, check=False)
    if tar.returncode != 0:
        raise SystemExit(f"--baseline {ref}: {tar.stderr.decode().strip()}")
    folder.mkdir()
    with tarfile.open(fileobj=io.BytesIO(tar.stdout)) as tf:
        tf.extractall(folder)  # this repository's own commit
    return folder


def _diagnose_motion(path: Path, out: Path, src: Path = ROOT) -> tuple[float, float, float, str]:
    """Wall time (s), CPU time (s), peak resident memory (MB) and the verdict's first line of
    `zrp diagnose-motion` in a fresh process running the code in ``src``."""
    code = ("import resource, sys; from zrp.cli import main; rc = main(sys.argv[1:]); "
            "print('PEAK_MB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); "
            "sys.exit(rc)")
    t0, c0 = time.perf_counter(), _cpu_children()
    proc = subprocess.run([sys.executable, "-c", code, "diagnose-motion", "--model", "puma",
                           "--data", str(path), "--frame", "base", "--out", str(out)],
                          cwd=src, capture_output=True, text=True, check=False,
                          env={**os.environ, "PYTHONPATH": str(src)})
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
    base = None
    for n in (400_000, 900_000):  # short comments on lines of their own (issue 35, #11)
        path = folder / f"short{n}.urdf"
        text = _urdf(10)
        path.write_text(text.replace("</robot>", "<!--a-->\n" * n + "</robot>"))
        cpu = _cpu(import_urdf, path)
        base = base or cpu
        rows.append((f"{n:,} short comment lines", f"{path.stat().st_size / 1e6:.1f}",
                     f"{cpu:.2f}", f"{cpu / base:.2f}" + (" (linear: about 2.25)"
                                                          if n == 900_000 else "")))
    for r in rows:
        print("URDF " + ", ".join(r))
    return rows


def _motion_rows(sizes: list[int], folder: Path, base_src: Path | None
                 ) -> list[tuple[str, ...]]:
    """One row per size: this checkout's figures, then (with a baseline) the baseline's and
    the ratios, both measured on the same file in the same run."""
    rows: list[tuple[str, ...]] = []
    base = None
    warm = _trajectory_csv(2000, folder)  # numba compiles into each checkout's cache first
    for i, src in enumerate((ROOT,) if base_src is None else (ROOT, base_src)):
        _diagnose_motion(warm, folder / f"warm{i}", src)
    for n in sizes:
        path = _trajectory_csv(n, folder)
        wall, cpu, peak, verdict = _diagnose_motion(path, folder / f"out{n}")
        per_row = cpu / n
        base = base or per_row
        print(f"{n:>10,} rows: wall {wall:.1f} s, CPU {cpu:.1f} s, peak {peak:.0f} MB, "
              f"CPU per row x {per_row / base:.2f} of {sizes[0]:,} rows; {verdict}")
        row = (f"{n:,}", f"{wall:.1f}", f"{cpu:.1f}", f"{peak:.0f}", f"{peak * 1024 / n:.1f}",
               f"{per_row / base:.2f}")
        if base_src is not None:
            bwall, _, bpeak, bverdict = _diagnose_motion(path, folder / f"base{n}", base_src)
            same = "same" if bverdict == verdict else f"baseline: {bverdict}"
            print(f"{n:>10,} rows, baseline: wall {bwall:.1f} s, peak {bpeak:.0f} MB; "
                  f"peak x {peak / bpeak:.2f}, wall x {wall / bwall:.2f}; verdict {same}")
            row += (f"{bpeak:.0f}", f"{peak / bpeak:.2f}", f"{bwall:.1f}", f"{wall / bwall:.2f}",
                    same)
        rows.append((*row, verdict))
        os.remove(path)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e5 rows at most")
    ap.add_argument("--rows", type=int, nargs="+", metavar="N",
                    help="trajectory sizes, rows (default 25,000 100,000 400,000 1,000,000; "
                         "--quick: the first two)")
    ap.add_argument("--baseline", metavar="REF",
                    help="also run each trajectory with the code of git commit REF in the same "
                         "run: ratios of peak memory and wall time to it")
    ap.add_argument("--skip-urdf", action="store_true", help="skip the URDF import rows")
    add_output_arguments(ap, "bench_input_scaling")
    args = ap.parse_args()
    out = output_path(args)
    report = Report("bench_input_scaling", "the cost of large trajectory and URDF inputs")
    sizes = args.rows or [25_000, 100_000] + ([] if args.quick else [400_000, 1_000_000])
    if any(n < 100 for n in sizes):
        ap.error(f"--rows: expected at least 100 rows each, got {sizes}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if not args.skip_urdf:
            report.table("URDF import (CPU time, best of 2)",
                         ["file", "MB", "CPU s", "ratio to 5,000 joints"], _urdf_rows(folder))
        base_src = None if args.baseline is None else _checkout(args.baseline, folder / "base")
        rows = _motion_rows(sizes, folder, base_src)
    cols = ["rows", "wall s", "CPU s", "peak MB", "peak KB per row",
            f"CPU per row / {sizes[0]:,} rows'"]
    if args.baseline is not None:
        cols += [f"peak MB at {args.baseline}", "peak ratio", f"wall s at {args.baseline}",
                 "wall ratio", "verdict at baseline"]
    report.table("`zrp diagnose-motion` in a fresh process on N rows (PUMA, 1 kHz, hidden "
                 "4 ms sync delay, 0.02 mm noise; before issue 26: 1e6 rows 434 s, 5.3 GB)",
                 [*cols, "verdict"], rows)
    report.write(out, args)


if __name__ == "__main__":
    main()
