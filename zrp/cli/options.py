"""Converters for command-line options (argparse ``type=``): every number a command takes is
checked here, once, with its range, so a bad value is one line naming the option
(``argument --seed: expected a whole number >= 0, got -1``) before any work starts.

The limits are stated where the options are declared; ``tests/cli/test_option_checks.py`` checks
that no command declares a bare ``type=int`` or ``type=float``.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING

from zrp.errors import InputError, UnitError
from zrp.limits import MAX_LENGTH, MAX_SEED

if TYPE_CHECKING:
    import numpy as np

    from zrp.model.manipulator import Manipulator

__all__ = [
    "DURATION",
    "FINITE",
    "FRACTION",
    "LENGTH",
    "LENGTH_UNIT",
    "MAX_FPS",
    "MAX_HEIGHT",
    "MAX_SECONDS",
    "MAX_STEPS",
    "MAX_WIDTH",
    "PERCENT",
    "SEED",
    "TOLERANCE",
    "add_deg",
    "add_progress",
    "draw_bar",
    "joint_angles",
    "real",
    "whole",
]

#: Most integration steps of a trajectory (ik, study, tolerance): the joint CSV of a million
#: steps is about 200 MB; finer steps change nothing measurable.
MAX_STEPS = 1_000_000
#: Largest video frame, pixels (4K UHD); MuJoCo's offscreen buffer fails far beyond it.
MAX_WIDTH, MAX_HEIGHT = 3840, 2160
#: Highest frame rate and longest video per segment: at most 72,000 frames, each rendered.
MAX_FPS, MAX_SECONDS = 120, 600.0


def whole(lo: int, hi: int | None = None) -> Callable[[str], int]:
    """A whole number in [lo, hi] (``hi`` None: no upper limit)."""

    def convert(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if v < lo or (hi is not None and v > hi):
            rng = f">= {lo}" if hi is None else f"from {lo} to {hi}"
            raise argparse.ArgumentTypeError(f"expected a whole number {rng}, got {text}")
        return v

    convert.__name__ = "whole number"
    return convert


def LENGTH_UNIT(text: str) -> str:
    """A length unit of :data:`zrp.units.LENGTH_UNITS` or an alias, canonical ("metres" -> "m");
    an unknown one is refused listing the known units."""
    from zrp.units import canonical_length_unit  # on use: keeps --help quick

    try:
        return canonical_length_unit(text, field="unit")
    except UnitError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("unit: ")) from None


LENGTH_UNIT.__name__ = "length unit"


def real(lo: float = -math.inf, hi: float = math.inf, *, open_lo: bool = False,
         open_hi: bool = False, unit: str = "") -> Callable[[str], float]:
    """A finite number in [lo, hi] (open ends with ``open_lo``/``open_hi``)."""

    def convert(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        ok = math.isfinite(v) and (v > lo if open_lo else v >= lo) and (
            v < hi if open_hi else v <= hi)
        if not ok:
            if math.isinf(lo) and math.isinf(hi):
                what = "a finite number"
            else:
                left, right = "(" if open_lo else "[", ")" if open_hi else "]"
                what = f"a number in {left}{lo:g}, {hi:g}{right}"
            raise argparse.ArgumentTypeError(f"expected {what}{' ' + unit if unit else ''}, "
                                             f"got {text}")
        return v

    convert.__name__ = "number"
    return convert


#: A random seed: 0 .. 2**63 - 1 (NumPy refuses negative seeds).
SEED = whole(0, MAX_SEED)
#: Any finite number (joint values, direction components).
FINITE = real()
#: A positive length (model length unit), at most the model's bound on lengths.
LENGTH = real(0.0, MAX_LENGTH, open_lo=True)
#: A tolerance or noise level: a length >= 0.
TOLERANCE = real(0.0, MAX_LENGTH)
#: A perturbation in percent, -1 < xi < 1 (eqs 8-12).
PERCENT = real(-1.0, 1.0, open_lo=True, open_hi=True, unit="%")
#: A fraction in [0, 1].
FRACTION = real(0.0, 1.0)
#: A duration, s.
DURATION = real(0.0, 1e6, open_lo=True, unit="s")


#: The help of ``--deg``, the same in every command (the rule of zrp/units.py).
DEG_HELP = ("angles in degrees: the values typed, the joint columns read that declare no unit, "
            "and the files written (declared q1[deg]); default rad")


def add_deg(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--deg``: one flag meaning the same in every command (:data:`DEG_HELP`)."""
    p.add_argument("--deg", action="store_true", help=DEG_HELP)


#: The help of ``--progress/--no-progress`` where a bar is drawn (tqdm): on a terminal only.
PROGRESS_HELP = ("show a progress bar on stderr when it is a terminal (default on; "
                 "--no-progress: none)")


def add_progress(p: argparse.ArgumentParser | argparse._ArgumentGroup,
                 help: str = PROGRESS_HELP) -> argparse.Action:
    """``--progress/--no-progress``: the one progress option of every command with a progress
    display, default on (tests/cli/test_one_name.py). A bar is drawn only on a terminal
    (:func:`draw_bar`): its carriage returns would garble a pipe or a log file; a command
    whose library prints plain periodic lines when piped (diagnose) says so in ``help``.
    Returns the action (for a deprecated alias such as render's ``--quiet``)."""
    return p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True,
                          help=help)


def draw_bar(args: argparse.Namespace) -> bool:
    """Draw a progress bar: ``--progress`` (the default) and stderr is a terminal."""
    return bool(args.progress) and sys.stderr is not None and sys.stderr.isatty()


def joint_angles(model: Manipulator, values: list[float] | np.ndarray, deg: bool,
                 option: str) -> np.ndarray:
    """Joint values typed after ``option`` (n values, or (n, 2) limits) to rad for the
    revolute joints (prismatic ones stay in the length unit), checked by zrp.units: a value
    that cannot be an angle in rad names ``option`` and suggests ``--deg``."""
    import numpy as np  # on use: keeps --help quick

    from zrp.units import angle_bounds, joint_values_to_rad  # on use: keeps --help quick

    q = np.asarray(values, dtype=float)
    if q.shape[0] != model.n:
        raise InputError(f"{option}: expected {model.n} values for {model.name!r} "
                         f"({', '.join(model.joint_names)}), got {q.shape[0]}")
    rows = q if q.ndim == 1 else q.reshape(model.n, -1).T  # limits: a row of lows, of highs
    out = joint_values_to_rad(rows, ~np.asarray(model.prismatic), "deg" if deg else "rad",
                              src=option, bounds=angle_bounds(model.lower, model.upper),
                              flag="--deg", header=False)
    return out if q.ndim == 1 else out.T.reshape(q.shape)
