"""How the dynamic gap diagnosis runs (:class:`DynamicsOptions`; the steps they tune are
in :mod:`zrp.gap.dynamics.diagnosis`)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DynamicsOptions"]


@dataclass(frozen=True)
class DynamicsOptions:
    """How the diagnosis runs (see the module docstring)."""

    window_s: float | None = None  # the derivative filter's window, s; None: chosen from
    # the data among WINDOWS (zrp.gap.dynamics.diagnosis)
    fit_rate_hz: float = 100.0
    folds: int = 5
    min_rel: float = 0.03
    min_abs: float = 0.05
    max_effects: int | None = None  # None: 3 a joint and 4 more (friction on every joint
    # takes up to three effects there, Coulomb, viscous and Stribeck)
    inertial: bool = True
    collinear: float = 0.1
    effects: tuple[str, ...] | None = None  # the effect names tried (None: all)
