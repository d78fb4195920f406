"""Measurement sets of every shape the readers accept, drawn from a seeded simulated PUMA.

A :class:`Shape` says how a set is laid out: how many poses and points, which points each pose
carries (the same on every pose; three points on some poses and one other on the rest;
points missing on some poses; one point label per run), orientation rows, repeated poses,
time, temperature and load columns, a joint that never moves, the frame. :func:`draw_set`
makes the set: the true robot is the PUMA with a joint offset and a link error, measured
through :func:`zrp.forward_kinematics` (not the fitting code) with seeded noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

import zrp
from zrp.gap import Measurements
from zrp.kinematics import uniform_joint_values
from zrp.rotations import matrix_from_rotvec

PUMA = zrp.load_model("puma")
LAYOUTS = ("same", "mixed", "missing", "runs")
#: the reflectors (mm) and the test point of the "mixed" layout.
TOOLS = np.array([(50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -70.0, 40.0),
                  (10.0, 10.0, 90.0)])
BASE_ROTVEC = np.array([0.02, -0.01, 0.8])
BASE_TRANSLATION = np.array([1500.0, -300.0, 200.0])


@dataclass(frozen=True)
class Shape:
    """How a drawn measurement set is laid out (module docstring)."""

    n_poses: int
    n_points: int
    layout: str
    quat: bool
    repeats: int
    t: bool
    temp: bool
    load: bool
    still: int | None
    frame: str
    seed: int


def _true_points(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions of every tool point (P, 4, 3) and the flange rotations (P, 3, 3) of the true
    robot (joint 2 offset 1 mrad, link 3 off by 0.3 mm), in the base frame."""
    bodies = np.array(PUMA.bodies, dtype=float)
    bodies[3] += (0.3, 0.0, -0.2)
    qa = q.copy()
    qa[:, 1] += 1e-3
    fk = zrp.forward_kinematics(PUMA.with_arrays(bodies=bodies), qa)
    return fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, TOOLS), fk.rotation


def _labels(shape: Shape, rng: np.random.Generator, P: int) -> list[list[int]]:
    """Per pose, the indices into :data:`TOOLS` it measures."""
    m = list(range(shape.n_points))
    if shape.layout == "mixed":
        return [m if i % 3 != 2 else [3] for i in range(P)]
    if shape.layout == "missing":
        out = []
        for _ in range(P):
            keep = [j for j in m if rng.random() > 0.3]
            out.append(keep or [int(rng.integers(shape.n_points))])
        return out
    if shape.layout == "runs":
        return [[min(shape.n_points * i // P, shape.n_points - 1)] for i in range(P)]
    return [m] * P


def draw_set(shape: Shape) -> Measurements:
    """The measurement set of ``shape`` (module docstring)."""
    rng = np.random.default_rng(shape.seed)
    q = uniform_joint_values(PUMA, shape.n_poses, rng, np.tile([-2.0, 2.0], (PUMA.n, 1)))
    if shape.still is not None:
        q[:, shape.still] = 0.3
    if shape.repeats:
        q = np.vstack([q, q[rng.choice(len(q), shape.repeats)]])
    P = len(q)
    pts, rot = _true_points(q)
    if shape.frame == "instrument":
        rb = matrix_from_rotvec(BASE_ROTVEC)
        pts = pts @ rb.T + BASE_TRANSLATION
        rot = rb @ rot
    pts = pts + rng.normal(scale=0.02, size=pts.shape)
    noise = Rotation.from_rotvec(rng.normal(scale=1e-4, size=(P, 3))).as_matrix()
    wxyz = Rotation.from_matrix(noise @ rot).as_quat()[:, [3, 0, 1, 2]]
    which = _labels(shape, rng, P)
    pose = np.concatenate([[i] * len(w) for i, w in enumerate(which)])
    point = np.concatenate(which)
    run = np.minimum(3 * pose // P, 2)
    return Measurements.from_arrays(
        np.array([f"P{i}" for i in pose]), q[pose], pts[pose, point],
        point=np.array([f"s{j + 1}" if j < 3 else "test" for j in point]), frame=shape.frame,
        t=10.0 * np.arange(len(pose)) if shape.t else None,
        temp=(20.0 + 5.0 * pose / P) if shape.temp else None,
        load=run.astype(float) if shape.load else None,
        quat=wxyz[pose] if shape.quat else None)
