"""Sim-to-real gap diagnosis: where the gap lies, which unmodelled effect causes it, and how
far it shrinks on withheld measurements (README.md in this folder).

In-process use::

    from zrp.gap import diagnose, load_measurements, write_outputs
    meas = load_measurements("D.csv", model, deg=True)
    diag = diagnose(model, meas, seed=0)
    diag.top_effect, diag.final.rms, diag.to_dict()
    write_outputs(diag, "DIR")  # diagnosis.json, report.md, residuals.csv, plots
"""

from zrp.gap.data import DataWarning as DataWarning
from zrp.gap.data import Measurements as Measurements
from zrp.gap.data import load_measurements as load_measurements
from zrp.gap.effects import EFFECTS as EFFECTS
from zrp.gap.effects import REGISTRATION as REGISTRATION
from zrp.gap.effects import Context as Context
from zrp.gap.effects import ParamSpec as ParamSpec
from zrp.gap.effects import effect_parameters as effect_parameters
from zrp.gap.fit import Aliased as Aliased
from zrp.gap.fit import FitResult as FitResult
from zrp.gap.fit import FitWarning as FitWarning
from zrp.gap.pipeline import Candidate as Candidate
from zrp.gap.pipeline import Diagnosis as Diagnosis
from zrp.gap.pipeline import GapWarning as GapWarning
from zrp.gap.pipeline import Metrics as Metrics
from zrp.gap.pipeline import NoiseFloor as NoiseFloor
from zrp.gap.pipeline import ParameterEstimate as ParameterEstimate
from zrp.gap.pipeline import Step as Step
from zrp.gap.pipeline import diagnose as diagnose
from zrp.gap.pipeline import noise_floor as noise_floor
from zrp.gap.pipeline import split_poses as split_poses
from zrp.gap.report import write_outputs as write_outputs
from zrp.gap.synthetic import Injection as Injection
from zrp.gap.synthetic import synthesize as synthesize

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
    "split_poses",
    "synthesize",
    "write_outputs",
]
