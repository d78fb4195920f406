"""Sim-to-real gap diagnosis: where the gap lies, which unmodelled effect causes it, and how
far it shrinks on withheld measurements (docs/diagnosis.md).

In-process use::

    from zrp.gap import diagnose, load_measurements
    meas = load_measurements("D.csv", model, deg=True)
    diag = diagnose(model, meas, seed=0)
    diag.top_effect, diag.final.rms, diag.to_dict()
    write_outputs(diag, "DIR")  # diagnosis.json, report.md, residuals.csv, plots
"""

from .data import DataWarning, Measurements, load_measurements
from .diagnose import (
    Candidate,
    Diagnosis,
    GapWarning,
    Metrics,
    NoiseFloor,
    ParameterEstimate,
    Step,
    diagnose,
    noise_floor,
    split_poses,
)
from .effects import EFFECTS, REGISTRATION, Context, ParamSpec, effect_parameters
from .fit import Aliased, FitResult, FitWarning
from .report import write_outputs
from .synthetic import Injection, random_poses, synthesize

__all__ = [
    "EFFECTS",
    "REGISTRATION",
    "Aliased",
    "Candidate",
    "Context",
    "DataWarning",
    "Diagnosis",
    "FitResult",
    "FitWarning",
    "GapWarning",
    "Injection",
    "Measurements",
    "Metrics",
    "NoiseFloor",
    "ParamSpec",
    "ParameterEstimate",
    "Step",
    "diagnose",
    "effect_parameters",
    "load_measurements",
    "noise_floor",
    "random_poses",
    "split_poses",
    "synthesize",
    "write_outputs",
]
