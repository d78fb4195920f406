"""Sim-to-real gap diagnosis: where the gap lies, which unmodelled effect causes it, and how
far it shrinks on withheld measurements (README.md in this folder).

In-process use::

    from zrp.gap import diagnose, load_measurements, write_outputs
    meas = load_measurements("D.csv", model, deg=True)
    diag = diagnose(model, meas, seed=0)
    diag.top_effect, diag.final.rms, diag.to_dict()
    write_outputs(diag, "DIR")  # diagnosis.json, report.md, residuals.csv, plots

The engine (every module but :mod:`zrp.gap.report`) never imports the report; the report's
wording of the verdict is installed into :class:`Diagnosis` here.
"""

from zrp.gap.assessment import Assessment as Assessment
from zrp.gap.assessment import Remainder as Remainder
from zrp.gap.baseline import GeometricBaseline as GeometricBaseline
from zrp.gap.csvfile import load_measurements as load_measurements
from zrp.gap.data import DataWarning as DataWarning
from zrp.gap.data import Measurements as Measurements
from zrp.gap.effects import EFFECTS as EFFECTS
from zrp.gap.effects import REGISTRATION as REGISTRATION
from zrp.gap.effects import Context as Context
from zrp.gap.effects import ParamSpec as ParamSpec
from zrp.gap.effects import effect_parameters as effect_parameters
from zrp.gap.leastsq import Aliased as Aliased
from zrp.gap.leastsq import FitResult as FitResult
from zrp.gap.leastsq import FitWarning as FitWarning
from zrp.gap.metrics import Metrics as Metrics
from zrp.gap.metrics import NoiseFloor as NoiseFloor
from zrp.gap.noise import noise_floor as noise_floor
from zrp.gap.options import DiagnosisOptions as DiagnosisOptions
from zrp.gap.pipeline import diagnose as diagnose
from zrp.gap.registration import Registration as Registration
from zrp.gap.report import write_outputs as write_outputs
from zrp.gap.report.verdict import verdict_text as _verdict_text
from zrp.gap.results import Candidate as Candidate
from zrp.gap.results import Diagnosis as Diagnosis
from zrp.gap.results import GapWarning as GapWarning
from zrp.gap.results import ParameterEstimate as ParameterEstimate
from zrp.gap.results import Step as Step
from zrp.gap.results import Where as Where
from zrp.gap.results import install_verdict_renderer as _install_verdict_renderer
from zrp.gap.split import split_poses as split_poses
from zrp.gap.synthetic import Injection as Injection
from zrp.gap.synthetic import synthesize as synthesize
from zrp.gap.where import WhereAnalysis as WhereAnalysis

_install_verdict_renderer(_verdict_text)

__all__ = [
    "EFFECTS",
    "REGISTRATION",
    "Aliased",
    "Assessment",
    "Candidate",
    "Context",
    "DataWarning",
    "Diagnosis",
    "DiagnosisOptions",
    "FitResult",
    "FitWarning",
    "GapWarning",
    "GeometricBaseline",
    "Injection",
    "Measurements",
    "Metrics",
    "NoiseFloor",
    "ParamSpec",
    "ParameterEstimate",
    "Registration",
    "Remainder",
    "Step",
    "Where",
    "WhereAnalysis",
    "diagnose",
    "effect_parameters",
    "load_measurements",
    "noise_floor",
    "split_poses",
    "synthesize",
    "write_outputs",
]
