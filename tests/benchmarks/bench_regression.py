"""Regression benchmark: realistic simulated sets, their final and baseline withheld errors.

The sets (tests/benchmarks/_regression_sets.py): a 7-axis arm at three payloads with a
compliant joint, a 6-D probe, near-collinear terms, an arm with parallel axes, few poses.
Each is diagnosed with the defaults (seed 0); the table gives the final model's withheld RMS
beside the plain complete geometric calibration's (the reference baseline) and, when it
differs, the physically held one's, the noise floor and the CPU time (process time; the load
average is in the file's header).

The check (``--check``; tests/contracts/test_regression_benchmark.py runs it, marked slow):
no set's final withheld RMS may exceed its value in the committed reference
``tests/benchmarks/regression_reference.json`` by more than :data:`TOLERANCE` (relative). The
reference is written only with ``--write-reference`` (and ``--force`` over an existing one),
after a change that is meant to move the numbers, and the commit says why.

Run: python3 tests/benchmarks/bench_regression.py [--quick] [--check] [--write-reference]
[--out FILE.md] [--force]  (writes renders/benchmarks/bench_regression.md and .json; --quick: the
sets at half size, for development: not comparable with the reference, so no --check).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

# this checkout's zrp and tests package (the sets use tests/measured.py), whatever is installed
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from _regression_sets import SETS
from _report import (
    Report,
    add_output_arguments,
    check_outputs,
    command_line,
    output_path,
)

from zrp.gap import diagnose

#: largest relative increase of a set's final withheld RMS over the reference that passes.
TOLERANCE = 0.05
REFERENCE = Path(__file__).resolve().parent / "regression_reference.json"


def run_set(name: str, size: float = 1.0) -> dict[str, Any]:
    """Diagnose one set: its withheld errors (model length unit), effects and CPU time."""
    arm, meas = SETS[name][1](size)
    t0, w0 = time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose(arm, meas, seed=0)
    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
    b = d.assessment.baseline
    return {"set": name, "poses": len(meas.pose_ids), "unit": d.length_unit,
            "final_rms": d.final.rms, "baseline_rms": b.withheld.rms,
            "held_baseline_rms": None if b.held is None else b.held.rms,
            "noise_floor_rms": d.noise_floor.rms,
            "effects": {k: list(v) for k, v in d.final_joints.items()},
            "cpu_s": cpu, "wall_s": wall}


def regressions(results: list[dict[str, Any]], reference: dict[str, Any]) -> list[str]:
    """The sets whose final RMS exceeds the reference's by more than its tolerance, in
    words (empty: none); a set missing from the reference is one too."""
    tol = float(reference["tolerance"])
    out = []
    for r in results:
        ref = reference["sets"].get(r["set"])
        if ref is None:
            out.append(f"{r['set']}: not in the reference (write it with --write-reference)")
        elif r["final_rms"] > ref["final_rms"] * (1.0 + tol):
            out.append(f"{r['set']}: final withheld RMS {r['final_rms']:.4g} > reference "
                       f"{ref['final_rms']:.4g} + {tol:.0%}")
    return out


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.4g}"


def _row(r: dict[str, Any], ref: dict[str, Any] | None) -> list[str]:
    nf = r["noise_floor_rms"]
    change = "-" if ref is None else f"{r['final_rms'] / ref['final_rms'] - 1.0:+.1%}"
    effects = "; ".join(f"{k} {','.join(map(str, v))}" for k, v in r["effects"].items())
    return [r["set"], SETS[r["set"]][0], str(r["poses"]), _fmt(r["final_rms"]),
            _fmt(r["baseline_rms"]), _fmt(r["held_baseline_rms"]), _fmt(nf),
            "-" if not nf else f"{r['final_rms'] / nf:.2f}", change, effects or "none",
            f"{r['cpu_s']:.1f}"]


def _write_reference(results: list[dict[str, Any]], args: argparse.Namespace) -> None:
    from zrp.output import write_json

    check_outputs(argparse.Namespace(replace=args.force), [REFERENCE])
    write_json(REFERENCE, {
        "comment": "final withheld RMS per set of tests/benchmarks/bench_regression.py; "
                   "the check fails when a set gets worse than this by more than tolerance",
        "command": command_line(), "tolerance": TOLERANCE,
        "sets": {r["set"]: {"final_rms": round(r["final_rms"], 6),
                            "baseline_rms": round(r["baseline_rms"], 6)} for r in results}},
        overwrite=args.force)
    print(f"wrote {REFERENCE.name}")


def _add_results(path: Path, results: list[dict[str, Any]]) -> None:
    """The unrounded numbers beside the table in the JSON just written (``results``)."""
    from zrp.output import write_json

    doc = json.loads(path.read_text(encoding="utf-8"))
    write_json(path, {**doc, "results": results}, overwrite=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the sets at half size (develop)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 when a set's final error is worse than the reference")
    ap.add_argument("--write-reference", action="store_true",
                    help="write tests/benchmarks/regression_reference.json (with --force "
                         "over an existing one)")
    add_output_arguments(ap, "bench_regression")
    args = ap.parse_args()
    if args.quick and (args.check or args.write_reference):
        ap.error("--quick runs are not comparable with the reference")
    if args.check and args.write_reference:
        ap.error("--check compares with the reference that --write-reference replaces")
    out = output_path(args)
    reference = (json.loads(REFERENCE.read_text(encoding="utf-8"))
                 if REFERENCE.is_file() else {"tolerance": TOLERANCE, "sets": {}})
    size = 0.5 if args.quick else 1.0
    results = []
    for name in SETS:
        r = run_set(name, size)
        results.append(r)
        print(" | ".join(_row(r, None if args.quick else reference["sets"].get(name))),
              flush=True)
    report = Report("bench_regression", "final and baseline withheld errors of realistic "
                                  "simulated sets")
    report.table(f"Withheld RMS ({results[0]['unit']}), size {size:g}",
                 ["set", "what", "poses", "final", "baseline (plain)", "baseline (held)",
                  "noise floor", "final / noise", "vs reference", "final model",
                  "CPU s"],
                 [_row(r, None if args.quick else reference["sets"].get(r["set"]))
                  for r in results],
                 note=f"Reference: tests/benchmarks/regression_reference.json; a set fails "
                      f"the check when its final RMS exceeds the reference by more than "
                      f"{TOLERANCE:.0%}. Baseline (plain): the unconstrained complete "
                      "geometric calibration; (held): the same held in the physical domains, "
                      "shown when it differs.")
    report.write(out, args)
    _add_results(out.with_suffix(".json"), results)
    if args.write_reference:
        _write_reference(results, args)
    if args.check:
        bad = regressions(results, reference)
        for b in bad:
            print(f"REGRESSION {b}", file=sys.stderr)
        raise SystemExit(1 if bad else 0)


if __name__ == "__main__":
    main()
