"""Benchmark: CPU time of the whole `zrp diagnose` against FIGAROH's geometric calibration.

On the regression benchmark's realistic simulated sets (tests/benchmarks/_regression_sets.py:
payloads with compliance, a 6-D probe, near-collinear terms, parallel axes, few poses) and two
of them at the sizes of the issue's slow real sets (the 6-D probe at 630 poses, the UR10 at
1,500 poses), three calls are timed in turn within each round (interleaved,
``_timing.interleaved``; the best of the rounds, CPU time of this process, all threads, the wall
time and the 1-minute load average beside it):

* ``zrp diagnose`` as a user runs it (the command's ``main`` in this process, the model TOML
  and the measurement CSV written before: reading, registration, the candidate search with its
  cross-validation, the baselines, the full-pose refit, the report files), with
  ``--no-plots``, and
* the same with its PNG plots;
* FIGAROH 1.0.2's ``initialize()`` + ``solve()`` (tests/benchmarks/_figaroh_geometric.py: its
  complete geometric calibration, 6 parameters per joint, the base and tip frames; positions
  and, on the 6-D set, orientations), on the same measurements.

The goal (issue 34): `zrp diagnose` no slower than FIGAROH on every set, orientations
included, while it fits more (a search over eight effects, cross-validated, against FIGAROH's
one geometric fit). FIGAROH's fit RMS is over all poses (it withholds none), shown to say that it
converged, not to rank accuracy.

Run: python3 tests/benchmarks/bench_figaroh.py [--quick] [--repeat N] [--no-readme]
[--out FILE.md] [--force]  (writes renders/benchmarks/bench_figaroh.md and .json, and the
generated table in zrp/gap/README.md; --quick: the five sets at size 1, one round each, the
README left as it is).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

# this checkout's zrp and tests package (the sets use tests/measured.py), whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from _figaroh_geometric import figaroh_available, figaroh_calibration
from _readme_block import replace_block
from _regression_sets import SETS
from _report import ROOT, Report, add_output_arguments, output_path
from _timing import interleaved

README = ROOT / "zrp" / "gap" / "README.md"
#: (label, regression set, size factor): the sets at their reference size, then two at the
#: sizes of the issue's slow real sets.
CASES = (*((name, name, 1.0) for name in SETS),
         ("probe_6d, 630 poses", "probe_6d", 3.15),
         ("parallel_axes, 1,500 poses", "parallel_axes", 7.5))
COLUMNS = ["set", "poses", "orientation", "zrp diagnose (CPU s)", "zrp diagnose (wall s)",
           "with plots (CPU s)", "FIGAROH (CPU s)", "FIGAROH (wall s)", "zrp / FIGAROH (CPU)",
           "goal", "load", "zrp final (withheld RMS)", "FIGAROH fit RMS (all poses)"]


def _zrp_command(arm: Any, meas: Any, work: Path, plots: bool) -> tuple[list[str], Path]:
    from zrp.model.files import save_model

    model, data = work / "model.toml", work / "data.csv"
    if not model.exists():
        save_model(arm, model)
        meas.to_csv(data)
    out = work / ("out_plots" if plots else "out")
    argv = ["diagnose", "--model", str(model), "--data", str(data), "--out", str(out),
            "--force", "--no-progress", *([] if plots else ["--no-plots"])]
    return argv, out


def _runner(argv: list[str]) -> Any:
    from zrp.cli.app import main

    def run() -> None:
        with contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if main(argv) != 0:
                raise SystemExit(f"zrp {' '.join(argv)} failed")
    return run


def run_case(label: str, name: str, size: float, repeat: int) -> list[str]:
    """Time one set; its table row."""
    arm, meas = SETS[name][1](size)
    orientation = meas.quat is not None
    found: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        argv, out = _zrp_command(arm, meas, work, plots=False)
        argv_plots, _ = _zrp_command(arm, meas, work, plots=True)
        fig, cleanup = figaroh_calibration(arm, meas, orientation=orientation)
        try:
            def peer() -> None:
                found["figaroh"] = fig()

            zrp_t, plots_t, fig_t = interleaved(_runner(argv), _runner(argv_plots), peer,
                                                repeat=repeat)
        finally:
            cleanup()
        diag = json.loads((out / "diagnosis.json").read_text(encoding="utf-8"))
    unit = diag.get("length_unit", "mm")
    ratio = zrp_t.cpu / fig_t.cpu
    f = found["figaroh"]
    return [label, str(len(meas.pose_ids)), "yes" if orientation else "no",
            f"{zrp_t.cpu:.2f}", f"{zrp_t.wall:.2f}", f"{plots_t.cpu:.2f}", f"{fig_t.cpu:.2f}",
            f"{fig_t.wall:.2f}", f"{ratio:.2f}", "PASS" if ratio <= 1.0 else "FAIL",
            f"{zrp_t.load[0]:.1f}-{zrp_t.load[1]:.1f}",
            f"{diag['final']['rms']:.4g} {unit}",
            f"{f['rms_mm']:.4g} mm ({f['parameters']} parameters"
            f"{'' if f['converged'] else ', not converged'})"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="the five sets at size 1, one round each; the README left as it is")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved rounds (default 3)")
    ap.add_argument("--no-readme", action="store_true",
                    help="leave zrp/gap/README.md's generated table as it is")
    add_output_arguments(ap, "bench_figaroh")
    args = ap.parse_args()
    why = figaroh_available()
    if why is not None:
        raise SystemExit(f"FIGAROH: {why} (pip install figaroh)")
    out = output_path(args)
    cases = CASES[:len(SETS)] if args.quick else CASES
    repeat = 1 if args.quick else args.repeat
    rows = []
    for label, name, size in cases:
        rows.append(run_case(label, name, size, repeat))
        print(" | ".join(rows[-1]), flush=True)
    report = Report("bench_figaroh", "CPU time of zrp diagnose against FIGAROH's geometric "
                                     "calibration")
    heading = (f"CPU time of the whole `zrp diagnose` against FIGAROH 1.0.2 `initialize()` + "
               f"`solve()` on the regression sets (best of {repeat} interleaved round"
               f"{'s' * (repeat > 1)}{', --quick' * args.quick}). Goal: zrp <= FIGAROH")
    report.table(heading, COLUMNS, rows,
                 note="CPU: process time (all threads) of the call, best of the rounds; load: "
                      "the 1-minute load average at the start and end of the set's rounds. zrp "
                      "diagnose: the command in this process (--no-plots; 'with plots': its PNG "
                      "plots too); it withholds a quarter of the poses and searches eight "
                      "effects. FIGAROH: its complete geometric calibration (6 parameters per "
                      "joint, base and tip frames) fitted to all poses "
                      "(tests/benchmarks/_figaroh_geometric.py).")
    report.write(out, args)
    if not (args.no_readme or args.out or args.quick):
        replace_block(README, "bench_figaroh", heading, COLUMNS, rows,
                      json.loads(out.with_suffix(".json").read_text(encoding="utf-8")))
        print(f"replaced the generated bench_figaroh table of {README.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
