"""The paper's video scenes: which arms, which joint path, which labels (NumPy only).

A scene is the content of a comparison video, assembled here in the core and drawn by the
simulation layer (``sim.render_video``, which takes the segments as they are):

* :func:`paper_video_scene`: the Table 1 PUMA drawing the 125 mm circle (the nominal inverse
  kinematics, :func:`zrp.paper.scenario.puma_circle_ik`), nominal ghost vs one parameter
  perturbed by xi percent (:class:`zrp.manufacturing.perturb.Perturbation`);
* :func:`teaching_sweep_scene`: the same circle once per perturbation level of the paper, in
  turn, so that the deviation visibly grows with xi.

Typical use (the command line's ``zrp render`` and ``zrp paper`` do this)::

    scene = paper_video_scene("JE2", 0.1, steps=360)
    sim.render_video(scene.segments, out_dir / scene.file_name, title=scene.title)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import end_effector_pose
from zrp.manufacturing.perturb import Perturbation
from zrp.manufacturing.study import PAPER_XI
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.paper.placement import RECOVERED, placement_path
from zrp.paper.scenario import puma_circle_ik

__all__ = [
    "PAPER_LEVELS",
    "Scene",
    "SceneSegment",
    "paper_magnification",
    "paper_video_file_name",
    "paper_video_scene",
    "perturbed_puma",
    "teaching_sweep_scene",
]


#: The paper's perturbation levels, percent (the non-negative half of the study's xi).
PAPER_LEVELS: tuple[float, ...] = tuple(x for x in PAPER_XI if x >= 0.0)


class SceneSegment(NamedTuple):
    """One part of a scene: the ``nominal`` and the ``perturbed`` arm along the joint path
    ``q(t)`` (t in s, shape (N,); q rad, shape (N, n)), titled ``label``. The field order is
    that of ``sim.VideoSegment``, so a segment is passed to the renderer as it is."""

    nominal: Manipulator
    perturbed: Manipulator
    t: F64
    q: F64
    label: str


@dataclass(frozen=True, eq=False)
class Scene:
    """A video's content.

    Attributes:
        segments: drawn one after the other, at one magnification.
        title: first line of the text on every frame.
        file_name: the video's file name (``.mp4``) in the output folder.
        magnify: the deviation magnification to draw (:func:`paper_magnification`: the same
            for every video of one parameter), or None for the renderer's automatic factor.
    """

    segments: tuple[SceneSegment, ...]
    title: str
    file_name: str
    magnify: float | None = None


def perturbed_puma(parameter: str, xi_percent: float) -> tuple[Manipulator, Manipulator, str]:
    """The Table 1 PUMA, its copy with ``parameter`` (LE<k> or JE<k>) perturbed by
    ``xi_percent``, and the label (perturbation and sign(0) convention)."""
    nominal = load_model("puma")
    pert = Perturbation.single(parameter, xi_percent)
    label = (f"{parameter} xi = {xi_percent:+g} %; sign(0): links {pert.sign_zero_links:d}, "
             f"axes {pert.sign_zero_axes:+d}")
    return nominal, pert.apply(nominal), label


def paper_magnification(parameter: str, q: F64) -> float:
    """The magnification every video of ``parameter`` is drawn at: the largest 1, 2 or 5 x
    10^k that makes the deviation at the paper's largest level (0.1 %) along the joint path
    ``q`` (rad, shape (N, 6)) at most a quarter of the circle's diameter (the rule of
    ``sim.nice_factor``), so a single video and a sweep of the same parameter match."""
    nominal, perturbed, _ = perturbed_puma(parameter, max(PAPER_LEVELS))
    p_n, _ = end_effector_pose(nominal, q)
    p_a, _ = end_effector_pose(perturbed, q)
    worst = float(np.max(np.linalg.norm(p_a - p_n, axis=-1)))
    span = float(np.linalg.norm(p_n.max(axis=0) - p_n.min(axis=0)))
    if not worst > 0:
        return 1.0
    x = 0.25 * span / worst
    e = math.floor(math.log10(x))
    return next((m * 10.0**e for m in (5.0, 2.0, 1.0) if m * 10.0**e <= x), 10.0**e)


def _circle(circle: str, steps: int) -> tuple[F64, F64]:
    """(t, q) of the named circle: "default" (:func:`puma_circle_ik`) or "recovered"
    (:data:`zrp.paper.placement.RECOVERED`)."""
    if circle == "recovered":
        path = placement_path(RECOVERED, steps)
        return np.asarray(path.t), np.asarray(path.q)
    if circle != "default":
        raise InputError(f"circle: expected 'default' or 'recovered', got {circle!r}")
    ik = puma_circle_ik(steps=steps)
    return np.asarray(ik.t), np.asarray(ik.q)


def paper_video_scene(parameter: str = "JE2", xi_percent: float = 0.1, *,
                      steps: int = 360, circle: str = "default") -> Scene:
    """The paper's 125 mm PUMA circle: nominal ghost vs one perturbed parameter.

    File ``puma_circle_<parameter>_<xi>pct.mp4``; ``steps``: inverse-kinematics steps;
    ``circle``: "default" or "recovered".
    """
    t, q = _circle(circle, steps)
    nominal, perturbed, label = perturbed_puma(parameter, xi_percent)
    seg = SceneSegment(nominal, perturbed, t, q, label)
    title = "PUMA, 125 mm circle" + (" (recovered)" if circle == "recovered" else "")
    return Scene((seg,), title, paper_video_file_name(parameter, xi_percent),
                 paper_magnification(parameter, seg.q))


def paper_video_file_name(parameter: str = "JE2", xi_percent: float = 0.1) -> str:
    """``puma_circle_<parameter>_<xi>pct.mp4``, the file :func:`paper_video_scene` names."""
    return f"puma_circle_{parameter}_{xi_percent:g}pct.mp4"


def teaching_sweep_scene(parameter: str = "JE2", levels: Sequence[float] = PAPER_LEVELS, *,
                         steps: int = 360) -> Scene:
    """Teaching demo: the PUMA circle at each perturbation level (percent) in turn.

    File ``puma_sweep_<parameter>.mp4``; drawn at one magnification, the deviation visibly
    grows with xi.
    """
    if len(levels) == 0:
        raise InputError("levels: expected at least one perturbation level (percent)")
    ik = puma_circle_ik(steps=steps)
    t, q = np.asarray(ik.t), np.asarray(ik.q)
    segs = []
    for xi in levels:
        nominal, perturbed, label = perturbed_puma(parameter, float(xi))
        segs.append(SceneSegment(nominal, perturbed, t, q, label))
    return Scene(tuple(segs), f"PUMA circle: {parameter} at the paper's levels",
                 f"puma_sweep_{parameter}.mp4", paper_magnification(parameter, q))
