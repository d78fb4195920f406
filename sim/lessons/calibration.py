"""Lesson 4: how a calibration finds a hidden backlash (the MuJoCo "real" robot measured like
a laser-tracker calibration, then :func:`zrp.gap.diagnose` on the measurements alone)."""

from __future__ import annotations

import numpy as np

from sim.lessons.lesson import Lesson, figure
from sim.robot.effect_specs import parse_effects
from sim.robot.instrument import random_instrument
from sim.robot.measurement import Procedure, measure
from sim.robot.real import RealRobot
from zrp.gap.pipeline import diagnose
from zrp.kinematics.sampling import reachable_poses
from zrp.model.files import load_model
from zrp.output import OutputDir

__all__ = ["CONCEPT", "FILES", "HIDDEN", "backlash_lesson"]

HIDDEN = "backlash:2=0.8mrad"
CONCEPT = ("A calibration compares where the robot should be with where a tracker sees it; a "
           "backlash of 0.8 mrad hidden in joint 2 leaves a gap the nominal model cannot "
           "explain, and the diagnosis names the effect and the joint from the measurements "
           "alone.")
FILES = ("lesson4_backlash.png",)


def backlash_lesson(out: OutputDir, small: bool = False) -> Lesson:
    """Measure the PUMA with a hidden joint-2 backlash at random poses (``small``: 40 poses,
    else 150; 0.02 mm tracker noise), diagnose, and plot the withheld RMS step by step."""
    model = load_model("puma")
    rng = np.random.default_rng(0)
    n = 40 if small else 150
    effects = parse_effects([HIDDEN], model, field="HIDDEN")
    q = reachable_poses(model, n, rng)
    inst = random_instrument(model, rng, 0.02)
    run = measure(RealRobot(model, effects), q, inst, rng, Procedure())
    diag = diagnose(model, run.measurements, seed=0)
    labels = ["nominal model\n(after registration)"]
    rms = [diag.nominal.rms]
    for st in diag.steps:
        labels.append(f"+ {st.effect}\njoints {','.join(map(str, st.joints))}")
        rms.append(st.withheld.rms)
    noise = diag.noise_floor.rms
    found = (f"{diag.steps[0].effect} on joint(s) {list(diag.steps[0].joints)}" if diag.steps
             else "no effect")
    with figure(out, FILES[0]) as (_, ax):
        ax.bar(range(len(rms)), rms, color=["tab:gray", *["tab:green"] * (len(rms) - 1)])
        ax.set_xticks(range(len(rms)), labels, fontsize=8)
        if noise:
            ax.axhline(noise, ls="--", color="tab:red", label=f"noise floor {noise:.3f} mm")
            ax.legend(fontsize=8)
        ax.set_ylabel("withheld RMS error (mm)")
        ax.set_title(f"hidden: {HIDDEN}; found first: {found} ({n} poses)")
    return Lesson("backlash", CONCEPT, (out.root / FILES[0],), {
        FILES[0]: f"The gap between model and tracker on poses withheld from fitting, before "
                  f"and after each effect the diagnosis added: it found {found} for a hidden "
                  f"{HIDDEN}."},
        {"poses": n, "found_first": found, "rms_nominal_mm": float(rms[0]),
         "rms_final_mm": float(diag.final.rms), "noise_floor_mm": float(noise or 0.0)})
