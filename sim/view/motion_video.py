"""The motion diagnosis as a video: the arm drawing its path, with the measured path, the
simulated path before and the simulated path after the diagnosed effects overlaid.

The paths come from :class:`zrp.gap.motion.MotionDiagnosis` (measurement frame), mapped into
the robot's base frame with the diagnosis's own registration. Their differences (tenths of a
millimetre) are magnified about the commanded path by a stated factor so that they show on a
metre-sized arm: drawn = before + M (path - before).
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np

from mjcf import MJCFOptions, build
from sim.view.render import OffscreenRenderer
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.motion import MotionDiagnosis, Trajectory
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path
from zrp.units import metres_per_unit

__all__ = ["render_motion_video"]

MEASURED = (0.1, 0.8, 0.2, 1.0)
BEFORE = (0.9, 0.2, 0.2, 1.0)
AFTER = (0.2, 0.4, 1.0, 1.0)


def _to_base(diag: MotionDiagnosis, pts: F64, scale: float) -> F64:
    if diag.registration is None:
        raise InputError("diag: has no registration (made by an older version?)")
    rot, trans = diag.registration
    return (pts - trans) @ rot * scale


def render_motion_video(model: Manipulator, traj: Trajectory, diag: MotionDiagnosis,
                        out_path: str | os.PathLike[str], *, magnify: float = 50.0,
                        fps: int = 30, width: int = 640, height: int = 480,
                        overwrite: bool = False) -> Path:
    """Write an mp4 of the arm (at the commanded joints) with the three paths overlaid
    (green measured, red simulated before, blue simulated after; differences x ``magnify``)."""
    import imageio_ffmpeg  # the project's mp4 writer (sim/README.md); only when a video is made

    if magnify <= 0 or fps < 1:
        raise InputError(f"magnify, fps: expected > 0 and >= 1, got {magnify}, {fps}")
    scale = metres_per_unit(model.length_unit, "model.length_unit")
    before = _to_base(diag, diag.path_before[:, 0], scale)
    paths = [(before + magnify * (_to_base(diag, p, scale) - before), rgba)
             for p, rgba in ((traj.xyz[:, 0], MEASURED), (diag.path_after[:, 0], AFTER))]
    paths.insert(1, (before, BEFORE))
    arm = build(model, MJCFOptions(inertia="none", offscreen_size=(width, height)))
    data = mujoco.MjData(arm.model)
    times = np.arange(traj.t[0], traj.t[-1], 1.0 / fps)
    idx = np.searchsorted(traj.t, times).clip(0, traj.n_samples - 1)
    centre = before.mean(axis=0)
    with OffscreenRenderer(arm.model, width, height) as r, \
            atomic_path(out_path, overwrite=overwrite) as tmp:
        gen = imageio_ffmpeg.write_frames(str(tmp), (width, height), fps=fps, codec="libx264",
                                          pix_fmt_out="yuv420p", macro_block_size=2,
                                          ffmpeg_log_level="error")
        gen.send(None)
        try:
            r.look_at(centre, 1.6, 150.0, -15.0)
            for tt, i in zip(times, idx, strict=True):
                data.qpos[arm.qpos_adr] = traj.q[i]
                mujoco.mj_kinematics(arm.model, data)
                r.update_scene(data)
                for pts, rgba in paths:
                    if i > 1:
                        r.add_polyline(pts[: i + 1: max(1, (i + 1) // 400)], rgba, 3.0)
                r.render()
                r.text(f"t = {tt:5.2f} s, differences x{magnify:g}\ngreen: measured\n"
                       f"red: sim before\nblue: sim + {', '.join(diag.effects)}",
                       f"\n\n\nRMS {diag.nominal.rms:.3f} {model.length_unit}\n"
                       f"RMS {diag.final.rms:.3f} {model.length_unit}")
                gen.send(np.ascontiguousarray(r.read()))
        finally:
            gen.close()
    return Path(out_path)
