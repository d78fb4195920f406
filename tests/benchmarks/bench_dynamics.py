"""The blind benchmark of the dynamic gap diagnosis: hidden dynamic effects on three arms,
each with its own inertias (the Menagerie UR5e, the PUMA 560, the Franka Panda URDF).

Per scenario the physics robot with one hidden effect (or none) is driven along a random
exciting Fourier command (20 s at 1 kHz, torque noise 1 % of each joint's torque range); the
log CSV is diagnosed blind (CSV + nominal arm only) and scored against the truth written
apart (:mod:`sim.studies.dynamics.benchmark`). Target: in >= 90 % of the visible single effects the
first effect named is the hidden one, on the right joint, and the withheld torque RMS is
<= 1.5x the true noise on every joint.

Run: python3 tests/benchmarks/bench_dynamics.py [--reps 2] [--seed 1] [--seconds 20]
[--arms ur5e puma panda] [--quick] [--out FILE.md] [--force] [--no-readme]   (writes
renders/benchmarks/bench_dynamics.md and .json; its first table, per arm, also replaces the
generated block of zrp/gap/dynamics/README.md, its heading saying the size of the run (arms,
effects, repetitions, log length, seed), reduced or --quick runs included; not with --out or
--no-readme)
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from _readme_block import replace_block
from _report import ROOT, Report, add_output_arguments, output_path

from sim.studies.dynamics import benchmark as bm
from sim.studies.dynamics.arms import available_arms
from sim.studies.dynamics.scenarios import KINDS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=2, help="scenarios per arm and effect")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--seconds", type=float, default=20.0, help="log length, s")
    ap.add_argument("--arms", nargs="*", default=None, help="default: every installed arm")
    ap.add_argument("--quick", action="store_true",
                    help="PUMA only, coulomb/payload/none, one 10 s log each (a smoke run)")
    ap.add_argument("--no-readme", action="store_true",
                    help="leave zrp/gap/dynamics/README.md's generated table as it is")
    add_output_arguments(ap, "bench_dynamics")
    args = ap.parse_args()
    out = output_path(args)
    arms = args.arms or available_arms()
    kinds = KINDS
    if args.quick:
        arms, kinds, args.reps, args.seconds = ["puma"], ("coulomb", "payload", "none"), 1, 10.0
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for sc in bm.draw_scenarios(arms, kinds, args.reps, args.seed, args.seconds):
            r = bm.run_scenario(sc, Path(work))
            print(f"{sc.name:24} named {r.named:14} ok={r.success} ratio "
                  f"{r.withheld_ratio:.2f}", flush=True)
            rows.append(r)
    report = Report("bench_dynamics", "blind benchmark of the dynamic gap diagnosis")
    heading = (f"{len(rows)} scenarios: arms {', '.join(arms)}; {len(kinds)} hidden effects "
               f"({', '.join(kinds)}) x {args.reps} per arm; {args.seconds:g} s logs at 1 kHz, "
               f"1 % torque noise; seed {args.seed}{' (--quick: a smoke run)' * args.quick}. "
               "Target: >= 90 % of the visible singles right")
    report.table(heading, BLOCK_COLUMNS, _per_arm(rows, arms),
                 note="right: the first effect named is the hidden one, on its joint, and the "
                      "withheld torque RMS <= 1.5x the noise on every joint; visibility: RMS of "
                      "the hidden effect's own torques over the noise, worst joint (< 1: not "
                      "visible, not counted)")
    t = bm.tally(rows)
    report.table("Summary", ["figure", "value", "target"], [
        ["visible single effects", t["visible_singles"], ""],
        ["right effect, joint and withheld <= 1.5 sigma", f"{t['right']} ({t['share']:.0%})",
         ">= 90 %"],
        ["of them named first (not as a reported tie)", t["right_named_first"], ""],
        ["'none' scenarios with nothing named", f"{t['none_clean']} of {t['none_scenarios']}",
         "all"],
        ["median withheld ratio (worst joint)", f"{t['median_ratio']:.2f}", "<= 1.5"]])
    for arm in arms:
        report.table(f"Per effect: {arm}", ["effect", "right / visible", "median ratio",
                                            "named"], _per_effect([r for r in rows
                                                                   if r.arm == arm]))
    report.table("Scenarios", ["arm", "effect", "seed", "joint", "visibility", "named",
                               "right", "withheld ratio", "shrink", "diagnosis s"],
                 [[r.arm, r.kind, r.seed, "" if r.joint is None else r.joint + 1,
                   f"{r.visibility:.1f}", r.named, r.success, f"{r.withheld_ratio:.2f}",
                   f"{r.shrink:.2f}", f"{r.seconds:.1f}"] for r in rows],
                 note="visibility: RMS of the hidden effect's own torques over the noise, "
                      "worst joint (< 1: not visible); shrink: withheld RMS after / before.")
    report.write(out, args)
    print(f"wrote {out}")
    if not (args.no_readme or args.out):
        replace_block(README, "bench_dynamics", heading, BLOCK_COLUMNS, _per_arm(rows, arms),
                      json.loads(out.with_suffix(".json").read_text(encoding="utf-8")))
        print(f"replaced the generated bench_dynamics table of {README.relative_to(ROOT)}")


README = ROOT / "zrp" / "gap" / "dynamics" / "README.md"
BLOCK_COLUMNS = ["arm", "visible singles", "right", "named first (not tied)",
                 "effect-free logs, nothing named", "withheld ratio, median (max)",
                 "visibility", "diagnosis s"]


def _per_arm(rows: list[bm.Row], arms: list[str]) -> list[list[object]]:
    """The README's table: per arm and for all, the tally (:func:`bm.tally`) and ranges."""
    keys = [*arms, "all"] if len(arms) > 1 else arms
    return [_arm_row(key, sel) for key in keys
            if (sel := [r for r in rows if key in ("all", r.arm)])]


def _span(values: list[float], fmt: str) -> str:
    return f"{min(values):{fmt}} to {max(values):{fmt}}" if values else "-"


def _arm_row(key: str, sel: list[bm.Row]) -> list[object]:
    t = bm.tally(sel)
    vis = [r for r in sel if r.kind != "none" and r.visible]
    ratio = [r.withheld_ratio for r in vis]
    lo_vis = f"{min(r.visibility for r in vis):.1f}" if vis else ""
    return [key, t["visible_singles"], f"{t['right']} ({t['share']:.0%})" if vis else "-",
            t["right_named_first"], f"{t['none_clean']} of {t['none_scenarios']}",
            f"{np.median(ratio):.2f} ({max(ratio):.2f})" if vis else "-",
            f"{lo_vis} to {max(r.visibility for r in vis):.0f}" if vis else "-",
            _span([r.seconds for r in sel], ".1f")]


def _per_effect(rows: list[bm.Row]) -> list[list[object]]:
    out = []
    for kind in KINDS:
        sel = [r for r in rows if r.kind == kind]
        vis = [r for r in sel if r.visible or kind == "none"]
        out.append([kind, f"{sum(r.success for r in vis)} / {len(vis)}",
                    f"{np.median([r.withheld_ratio for r in sel]):.2f}" if sel else "",
                    ", ".join(r.named for r in sel)])
    return out


if __name__ == "__main__":
    main()
