"""Benchmark: the full candidate search of ``zrp diagnose`` on 1,000 measured points.

Goal (issue 5): <= 10 s on this machine for 1,000 points (500 poses x 2 reflectors), all
eight candidate effects, up to four greedy steps, 5-fold cross-validation, identifiability
survey and "where" analysis. The baseline measured in the same run is the registration fit
alone (the least any diagnosis must do), so the printed ratio says what the search costs on
top of it, independent of the machine's load.

Run: python tests/benchmarks/bench_diagnose.py
"""

from __future__ import annotations

import time
import warnings

import numpy as np

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


def _best(fn, repeats=3):
    best = np.inf
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    rng = np.random.default_rng(2024)
    print(f"{'robot':<28}{'points':>7}{'registration s':>16}{'full search s':>15}"
          f"{'ratio':>8}{'goal':>8}  found")
    for model in (zrp.load_model("puma"), IRB120):
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

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            diagnose(model, meas, seed=0, effects=("joint_offset",))  # warm-up (imports)
            t_base, _ = _best(registration)
            t_full, d = _best(lambda model=model, meas=meas: diagnose(model, meas, seed=0))
        ok = "PASS" if t_full <= GOAL_S else "FAIL"
        print(f"{model.name[:27]:<28}{meas.n_rows:>7}{t_base:>16.3f}{t_full:>15.3f}"
              f"{t_full / t_base:>8.1f}{ok:>8}  {', '.join(d.effects)} "
              f"(withheld RMS {d.nominal.rms:.3f} -> {d.final.rms:.3f} mm)")


if __name__ == "__main__":
    main()
