"""Lessons 1 and 2: what a joint-axis tilt does along the circle, and why a link error
leaves the orientation alone (the paper's 125 mm PUMA circle, :mod:`zrp.paper`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.lessons.lesson import Lesson, figure
from sim.view.frames import VideoOptions
from sim.view.video import render_video
from zrp.manufacturing.perturb import Perturbation
from zrp.manufacturing.study import one_at_a_time
from zrp.output import OutputDir
from zrp.paper.scenario import circle_joint_path, puma_circle
from zrp.paper.scenes import paper_video_scene

__all__ = ["LINKS_CONCEPT", "LINKS_FILES", "TILT_CONCEPT", "TILT_FILES", "links_lesson",
           "tilt_lesson"]

TILT_CONCEPT = ("A joint axis tilted by alpha turns the hand by theta = 2 |sin(q_k / 2)| alpha "
                "(to first order): the error grows with how far that joint has turned from the "
                "zero reference, so it changes along the circle.")
TILT_FILES = ("lesson1_tilt_angle.png", "lesson1_tilt_circle.mp4")
LINKS_CONCEPT = ("A link-length error moves the tool by exactly xi ||b_k|| at every instant "
                 "and never turns it: the error angle is exactly 0.")
LINKS_FILES = ("lesson2_link_error.png",)


def tilt_lesson(out: OutputDir, small: bool = False) -> Lesson:
    """JE2 at 0.1 % along the circle: measured error angle against 2 |sin(q_2 / 2)| alpha,
    and a short video of the arm (``small``: 120 IK steps, 1.5 s at 10 fps, 320 x 240)."""
    steps = 120 if small else 360
    model = puma_circle().model
    path = circle_joint_path(model, steps=steps)
    st = one_at_a_time(model, path, ("JE2",), (0.1,))
    alpha = float(np.arctan(np.sqrt(2.0) * 1e-3 / (1.0 + 1e-3)))   # the eq (10) tilt, rad
    dq = path.q[:, 1]                                               # q_2 from the zero reference
    closed = 2.0 * np.abs(np.sin(dq / 2.0)) * alpha
    theta = st.angle_rad[0, 0]
    worst = float(np.max(np.abs(theta - closed)) / max(float(closed.max()), 1e-300))
    with figure(out, TILT_FILES[0], 2) as (_, (a1, a2)):
        a1.plot(path.t, 1e3 * theta, "-", lw=2.5, color="tab:purple",
                label="error angle theta, measured (perturbed FK)")
        a1.plot(path.t, 1e3 * closed, "--", lw=1.5, color="k",
                label="2 |sin(q2 / 2)| alpha (closed form)")
        a1.set_ylabel("theta (mrad)")
        a1.legend(fontsize=8)
        a1.set_title("JE2 tilted by alpha = sqrt(2) xi / (1 + xi), xi = 0.1 %")
        a2.plot(path.t, np.degrees(dq), color="tab:blue")
        a2.set_ylabel("q2 (deg)")
        a2.set_xlabel("time (s)")
    opts = (VideoOptions(width=320, height=240, fps=10, seconds=1.5) if small
            else VideoOptions(seconds=4.0))
    scene = paper_video_scene("JE2", 0.1, steps=steps)
    with out.path(TILT_FILES[1]) as tmp:
        res = render_video(scene.segments, tmp, title="Lesson 1: a tilted joint axis",
                           options=replace(opts, magnify=scene.magnify, format="mp4"),
                           overwrite=True, progress=False)
    files = (out.root / TILT_FILES[0], out.root / TILT_FILES[1])
    return Lesson("tilt", TILT_CONCEPT, files, {
        TILT_FILES[0]: "The error angle of a 0.1 % JE2 tilt along the circle beside the closed "
                       "form 2 |sin(q2/2)| alpha: the two curves lie on each other.",
        TILT_FILES[1]: "The arm drawing the circle with JE2 tilted, deviations magnified "
                       f"x{res.magnify:g}: the actual path leaves the desired one where q2 "
                       "has turned most."},
        {"max_theta_rad": float(theta.max()), "closed_form_rel_error": worst})


def links_lesson(out: OutputDir, small: bool = False) -> Lesson:
    """LE3 at 0.1 %: delta_p constant at xi ||b_3||, error angle identically 0."""
    model = puma_circle().model
    path = circle_joint_path(model, steps=120 if small else 360)
    st = one_at_a_time(model, path, ("LE3", "JE3"), (0.1,))
    b3 = float(np.linalg.norm(model.bodies[2]))
    pert = Perturbation.single("LE3", 0.1)
    with figure(out, LINKS_FILES[0], 2) as (_, (a1, a2)):
        a1.plot(path.t, st.delta_p[0, 0], lw=2.5, color="tab:orange", label="LE3, xi = 0.1 %")
        a1.axhline(1e-3 * b3, ls="--", color="k", label=f"xi ||b3|| = {1e-3 * b3:.4f} mm")
        a1.plot(path.t, st.delta_p[1, 0], ":", color="tab:green", label="JE3, xi = 0.1 %")
        a1.set_ylabel("delta_p (mm)")
        a1.legend(fontsize=8)
        a1.set_title(f"link error vs axis error ({pert.convention.split(';')[0]})")
        a2.plot(path.t, 1e3 * st.angle_rad[0, 0], lw=2.5, color="tab:orange",
                label="LE3: exactly 0")
        a2.plot(path.t, 1e3 * st.angle_rad[1, 0], ":", color="tab:green", label="JE3")
        a2.set_ylabel("error angle theta (mrad)")
        a2.set_xlabel("time (s)")
        a2.legend(fontsize=8)
    return Lesson("links", LINKS_CONCEPT, (out.root / LINKS_FILES[0],), {
        LINKS_FILES[0]: "A 0.1 % LE3 error moves the tool by a constant 0.4318 mm and turns it "
                        "by exactly 0, while a JE3 tilt of the same size both moves and turns "
                        "it by amounts that change along the circle."},
        {"le3_max_angle_rad": float(st.angle_rad[0, 0].max()),
         "le3_delta_p_spread_mm": float(np.ptp(st.delta_p[0, 0])),
         "le3_delta_p_mm": float(st.delta_p[0, 0].max())})
