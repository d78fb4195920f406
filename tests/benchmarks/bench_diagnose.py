"""Benchmark: the full candidate search of ``zrp diagnose`` on 1,000 measured points.

Goal (issue 5): <= 10 s on this machine for 1,000 points (500 poses x 2 reflectors), all
eight candidate effects, up to four greedy steps, 5-fold cross-validation, identifiability
survey and "where" analysis. The baseline measured in the same run is the registration fit
alone (the least any diagnosis must do), so the printed ratio says what the search costs on
top of it. Times are CPU time (process time), the registration and the search timed in turn
within each round (interleaved, ``_timing.interleaved``), with the wall time and the load
average beside them, so that a busy machine does not move the figures.

Run: python3 tests/benchmarks/bench_diagnose.py [--quick] [--out FILE.md] [--force]
(writes the table to renders/benchmarks/bench_diagnose.md and .json; --quick: the PUMA only).
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np
from _report import Report, add_output_arguments, output_path
from _timing import interleaved

import zrp
from zrp.gap import Injection, diagnose, synthesize
from zrp.gap.fit.leastsq import fit, initial_registration
from zrp.gap.model.context import Context
from zrp.gap.model.effects import registration_parameters
from zrp.kinematics import uniform_joint_values

GOAL_S = 10.0
IRB120 = zrp.Manipulator.from_arrays(
    axes=[[0, 0, 1], [0, 1, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]],
    bodies=[[0, 0, 0], [0, 0, 290], [0, 0, 270], [0, 0, 70], [302, 0, 0], [0, 0, 0],
            [72, 0, 0]],
    axial=[1, 0, 0], transverse=[0, 1, 0], name="ABB IRB 120 (datasheet)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the PUMA only")
    add_output_arguments(ap, "bench_diagnose")
    args = ap.parse_args()
    out = output_path(args)
    rng = np.random.default_rng(2024)
    rows = []
    print(f"{'robot':<28}{'points':>7}{'registr. CPU s':>16}{'search CPU s':>15}"
          f"{'ratio':>8}{'goal':>8}  found")
    for model in (zrp.load_model("puma"),) + (() if args.quick else (IRB120,)):
        q = uniform_joint_values(model, 500, rng)
        inj = Injection(joint_offset={2: 1e-3}, compliance={2: 2e-5, 3: 3e-5},
                        masses={"p3": 8.0, "ee": 3.0})
        meas = synthesize(model, q, inj, rng=rng, noise_sigma=0.02,
                          tool_offsets=((50.0, 0.0, 30.0), (-40.0, 60.0, 30.0)))
        assert meas.n_rows == 1000
        ctx = Context(model, meas)
        poses = np.arange(len(meas.pose_ids))
        specs = registration_parameters(ctx)

        def registration(ctx=ctx, specs=specs, poses=poses):
            th0, rb0 = initial_registration(ctx, specs, poses)
            return fit(ctx, specs, poses, th0, rb0)

        found = {}

        def full(model=model, meas=meas, found=found):
            found["d"] = diagnose(model, meas, seed=0)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            diagnose(model, meas, seed=0, effects=("joint_offset",))  # warm-up (imports)
            base_t, full_t = interleaved(registration, full, repeat=3)
        d, t_base, t_full = found["d"], base_t.cpu, full_t.cpu
        ok = "PASS" if t_full <= GOAL_S else "FAIL"
        found_txt = (f"{', '.join(d.effects)} (withheld RMS {d.nominal.rms:.3f} -> "
                     f"{d.final.rms:.3f} mm)")
        print(f"{model.name[:27]:<28}{meas.n_rows:>7}{t_base:>16.3f}{t_full:>15.3f}"
              f"{t_full / t_base:>8.1f}{ok:>8}  {found_txt}  (wall {full_t.wall:.3f} s, "
              f"load {full_t.load[0]:.1f}-{full_t.load[1]:.1f})")
        rows.append((model.name, f"{meas.n_rows:,}", f"{t_base:.3f}", f"{t_full:.3f}",
                     f"{full_t.wall:.3f}", f"{t_full / t_base:.1f}x",
                     f"{full_t.load[0]:.1f}-{full_t.load[1]:.1f}",
                     f"<= {GOAL_S:g} s: {ok}", found_txt))
    report = Report("bench_diagnose", "the full candidate search of the gap diagnosis")
    report.table("1,000 synthetic points (500 poses x 2 reflectors, 0.02 mm noise; best of 3 "
                 "interleaved rounds)",
                 ["robot", "points", "registration fit (CPU s)", "full search (CPU s)",
                  "full search (wall s)", "ratio (CPU)", "load average", "goal", "found"],
                 rows, note="CPU: process time of the call (all threads); the registration "
                            "fit and the full search timed in turn within each round.")
    report.write(out, args)


if __name__ == "__main__":
    main()
