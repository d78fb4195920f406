"""Sim-to-real gap diagnosis: where the gap lies, which unmodelled effect causes it, and how
far it shrinks on withheld measurements (docs/diagnosis.md).

In-process use::

    from zrp.gap import diagnose, load_measurements
    meas = load_measurements("D.csv", model, deg=True)
    diag = diagnose(model, meas, seed=0)
    diag.top_effect, diag.final.rms, diag.to_dict()
    write_outputs(diag, "DIR")  # diagnosis.json, report.md, residuals.csv, plots
"""

import importlib
from typing import Any

# Submodules load on first use: `zrp.gap.effects` (needed to list the effects when the CLI
# builds its parser) must not pull in the fitting code and scipy.stats (about 1 s).
_WHERE = {
    "DataWarning": "data",
    "Measurements": "data",
    "load_measurements": "data",
    "Candidate": "diagnose",
    "Diagnosis": "diagnose",
    "GapWarning": "diagnose",
    "Metrics": "diagnose",
    "NoiseFloor": "diagnose",
    "ParameterEstimate": "diagnose",
    "Step": "diagnose",
    "diagnose": "diagnose",
    "noise_floor": "diagnose",
    "split_poses": "diagnose",
    "EFFECTS": "effects",
    "REGISTRATION": "effects",
    "Context": "effects",
    "ParamSpec": "effects",
    "effect_parameters": "effects",
    "Aliased": "fit",
    "FitResult": "fit",
    "FitWarning": "fit",
    "write_outputs": "report",
    "Injection": "synthetic",
    "random_poses": "synthetic",
    "synthesize": "synthetic",
}

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


def __getattr__(name: str) -> Any:
    mod = _WHERE.get(name)
    if mod is None:
        raise AttributeError(f"module 'zrp.gap' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{mod}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
