"""Sim-to-real gap diagnosis: where the gap lies, which unmodelled effect causes it, and how
far it shrinks on withheld measurements (README.md in this folder).

In-process use::

    from zrp.gap import diagnose, load_measurements, write_outputs
    meas = load_measurements("D.csv", model, deg=True)
    diag = diagnose(model, meas, seed=0)
    diag.top_effect, diag.final.rms, diag.to_dict()
    zrp.gap.report.verdict_text(diag)  # the verdict in plain words
    write_outputs(diag, "DIR")  # diagnosis.json, report.md, residuals.csv, plots

The engine (every module but :mod:`zrp.gap.report`) never imports the report; the report is a
plain function of the result (``zrp.gap.report.verdict_text(diag)``).
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "Assessment": "zrp.gap.analysis.assessment",
    "Remainder": "zrp.gap.analysis.assessment",
    "GeometricBaseline": "zrp.gap.analysis.baseline",
    "GapWarning": "zrp.gap.analysis.checks",
    "WhereAnalysis": "zrp.gap.analysis.where",
    "load_measurements": "zrp.gap.data.csvfile",
    "DataWarning": "zrp.gap.data.measurements",
    "Measurements": "zrp.gap.data.measurements",
    "NoiseFloor": "zrp.gap.data.noise",
    "noise_floor": "zrp.gap.data.noise",
    "split_poses": "zrp.gap.data.split",
    "Injection": "zrp.gap.data.synthetic",
    "synthesize": "zrp.gap.data.synthetic",
    "Aliased": "zrp.gap.fit.aliasing",
    "FitResult": "zrp.gap.fit.leastsq",
    "FitWarning": "zrp.gap.fit.leastsq",
    "Metrics": "zrp.gap.fit.metrics",
    "Registration": "zrp.gap.fit.registration",
    "HeldDirection": "zrp.gap.fit.wellposed",
    "EFFECTS": "zrp.gap.model.context",
    "REGISTRATION": "zrp.gap.model.context",
    "Context": "zrp.gap.model.context",
    "ParamSpec": "zrp.gap.model.context",
    "Domain": "zrp.gap.model.domains",
    "domain_violations": "zrp.gap.model.domains",
    "parameter_domain": "zrp.gap.model.domains",
    "effect_parameters": "zrp.gap.model.effects",
    "DiagnosisOptions": "zrp.gap.options",
    "diagnose": "zrp.gap.pipeline",
    "write_outputs": "zrp.gap.report",
    "Diagnosis": "zrp.gap.results",
    "Where": "zrp.gap.results",
    "Candidate": "zrp.gap.search.steps",
    "ParameterEstimate": "zrp.gap.search.steps",
    "Step": "zrp.gap.search.steps",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.gap.analysis.assessment import Assessment as Assessment
    from zrp.gap.analysis.assessment import Remainder as Remainder
    from zrp.gap.analysis.baseline import GeometricBaseline as GeometricBaseline
    from zrp.gap.analysis.checks import GapWarning as GapWarning
    from zrp.gap.analysis.where import WhereAnalysis as WhereAnalysis
    from zrp.gap.data.csvfile import load_measurements as load_measurements
    from zrp.gap.data.measurements import DataWarning as DataWarning
    from zrp.gap.data.measurements import Measurements as Measurements
    from zrp.gap.data.noise import NoiseFloor as NoiseFloor
    from zrp.gap.data.noise import noise_floor as noise_floor
    from zrp.gap.data.split import split_poses as split_poses
    from zrp.gap.data.synthetic import Injection as Injection
    from zrp.gap.data.synthetic import synthesize as synthesize
    from zrp.gap.fit.aliasing import Aliased as Aliased
    from zrp.gap.fit.leastsq import FitResult as FitResult
    from zrp.gap.fit.leastsq import FitWarning as FitWarning
    from zrp.gap.fit.metrics import Metrics as Metrics
    from zrp.gap.fit.registration import Registration as Registration
    from zrp.gap.fit.wellposed import HeldDirection as HeldDirection
    from zrp.gap.model.context import EFFECTS as EFFECTS
    from zrp.gap.model.context import REGISTRATION as REGISTRATION
    from zrp.gap.model.context import Context as Context
    from zrp.gap.model.context import ParamSpec as ParamSpec
    from zrp.gap.model.domains import Domain as Domain
    from zrp.gap.model.domains import domain_violations as domain_violations
    from zrp.gap.model.domains import parameter_domain as parameter_domain
    from zrp.gap.model.effects import effect_parameters as effect_parameters
    from zrp.gap.options import DiagnosisOptions as DiagnosisOptions
    from zrp.gap.pipeline import diagnose as diagnose
    from zrp.gap.report import write_outputs as write_outputs
    from zrp.gap.results import Diagnosis as Diagnosis
    from zrp.gap.results import Where as Where
    from zrp.gap.search.steps import Candidate as Candidate
    from zrp.gap.search.steps import ParameterEstimate as ParameterEstimate
    from zrp.gap.search.steps import Step as Step

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
    "Domain",
    "FitResult",
    "FitWarning",
    "GapWarning",
    "GeometricBaseline",
    "HeldDirection",
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
    "domain_violations",
    "effect_parameters",
    "load_measurements",
    "noise_floor",
    "parameter_domain",
    "split_poses",
    "synthesize",
    "write_outputs",
]
