"""What an instrument measures on a robot the tests know exactly: computed with
:func:`zrp.forward_kinematics` of the true model (not with the fitting code under test),
registered into the instrument's frame and with seeded noise.

* :func:`full_pose_measurements`: a laser tracker's reflector positions and a probe's
  orientations on static poses of an arm with a tilted axis (and joint offsets), as
  :class:`zrp.gap.Measurements` (the full-pose identification, diagnosis and calibration tests).
* :func:`puma_full_pose`: the one such data set the calibration and diagnosis tests share.
* :func:`tracked_tool_point`: a tracker following one tool point along a joint trajectory
  (the motion diagnosis tests).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

import zrp
from zrp.gap import Measurements
from zrp.kinematics import uniform_joint_values
from zrp.kinematics.identification import axis_tangents
from zrp.rotations import matrix_from_rotvec

#: The tracker's frame seen from the robot base: rotation and translation (mm).
BASE_ROTATION = Rotation.from_rotvec([0.02, -0.01, 0.8]).as_matrix()
BASE_TRANSLATION = np.array([1500.0, -300.0, 200.0])


def full_pose_measurements(model: zrp.Manipulator, n_poses: int, seed: int, *,
                           tilt: tuple[int, int, float], tools: ArrayLike,
                           probe_rotation: NDArray[np.float64], sigma_orientation: float,
                           joint_offset: Mapping[int, float] | None = None,
                           sigma_position: float = 0.02, quat: bool = True,
                           span_rad: float = 2.5) -> Measurements:
    """Positions of every tool point and the flange orientation of ``n_poses`` random poses.

    The true robot is ``model`` with joint ``tilt[0]``'s (1-based) axis turned by ``tilt[2]``
    rad towards its tangent ``tilt[1]`` (0 or 1, :func:`axis_tangents`), u' = (u + a t) / |.|,
    and the joint values shifted by ``joint_offset`` {joint: rad} (the data record the
    commanded values). Poses are uniform in +-``span_rad`` rad (default 2.5), drawn from
    ``default_rng(seed)``;
    then the position noise (``sigma_position`` per coordinate), then the orientation noise
    (rotation vectors of ``sigma_orientation`` rad per component) are drawn from the same
    generator. The measured orientation is noise @ R_b @ R_n @ ``probe_rotation``, with the
    registration R_b, t_b of :data:`BASE_ROTATION`, :data:`BASE_TRANSLATION`. Without
    ``quat`` the orientation columns are left out (same positions).
    """
    rng = np.random.default_rng(seed)
    tools = np.atleast_2d(np.asarray(tools, dtype=float))
    m = len(tools)
    q = uniform_joint_values(model, n_poses, rng, np.tile([-span_rad, span_rad], (model.n, 1)))
    joint, tangent, angle = tilt
    axes = np.array(model.axes, dtype=float)
    v = axes[joint - 1] + angle * axis_tangents(axes[joint - 1])[tangent]
    axes[joint - 1] = v / np.linalg.norm(v)
    shift = np.zeros(model.n)
    for k, value in (joint_offset or {}).items():
        shift[k - 1] = value
    fk = zrp.forward_kinematics(model.with_arrays(axes=axes), q + shift)
    y = fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, tools)
    xyz = y @ BASE_ROTATION.T + BASE_TRANSLATION + rng.normal(scale=sigma_position,
                                                              size=y.shape)
    noise = Rotation.from_rotvec(rng.normal(scale=sigma_orientation,
                                            size=(n_poses, 3))).as_matrix()
    rot = noise @ BASE_ROTATION @ fk.rotation @ probe_rotation
    wxyz = Rotation.from_matrix(rot).as_quat()[:, [3, 0, 1, 2]]
    points = [f"s{k}" for k in range(1, m + 1)]
    return Measurements.from_arrays(np.repeat(np.arange(n_poses), m), np.repeat(q, m, axis=0),
                                    xyz.reshape(-1, 3), point=np.tile(points, n_poses),
                                    quat=np.repeat(wxyz, m, axis=0) if quat else None)


#: The calibration data's probe (flange to orientation sensor) rotation and reflectors (mm).
PROBE_ROTATION = Rotation.from_rotvec([0.2, 0.1, -0.3]).as_matrix()
REFLECTORS = np.array([(50.0, 0.0, 30.0), (-40.0, 60.0, 30.0), (0.0, -70.0, 40.0)])


def puma_full_pose(quat: bool = True) -> Measurements:
    """The full-pose calibration data of the calibration and diagnosis tests: the PUMA with
    joint 2 off by 1 mrad and axis 5 tilted 1.5 mrad (first tangent), 150 poses x 3
    :data:`REFLECTORS`, orientation noise 1e-4 rad, probe :data:`PROBE_ROTATION`."""
    return full_pose_measurements(zrp.load_model("puma"), 150, 7, tilt=(5, 0, 1.5e-3),
                                  joint_offset={2: 1e-3}, tools=REFLECTORS,
                                  probe_rotation=PROBE_ROTATION, sigma_orientation=1e-4,
                                  quat=quat)


#: The motion tests' tool point on the flange (mm) and the tracker's registration.
TRACKED_TOOL = np.array([40.0, 10.0, 30.0])
TRACKER_ROTVEC = (0.1, -0.2, 0.3)
TRACKER_TRANSLATION = np.array([1500.0, -200.0, 300.0])


def tracked_tool_point(model: zrp.Manipulator, q_actual: ArrayLike, rng: np.random.Generator,
                       sigma: float = 0.02) -> NDArray[np.float64]:
    """The tracker's reading of :data:`TRACKED_TOOL` at the joint values ``q_actual`` (shape
    (T, n)), in the tracker's frame, with ``sigma`` mm of noise per coordinate: shape (T, 3)."""
    fk = zrp.forward_kinematics(model, q_actual)
    x = fk.position + fk.rotation @ TRACKED_TOOL
    x = x @ matrix_from_rotvec(TRACKER_ROTVEC).T + TRACKER_TRANSLATION
    return x + rng.normal(0.0, sigma, x.shape)
