# %% [markdown]
# # 1. ZRP kinematics and the Euler-Rodrigues parameters
#
# The zero-reference-position (ZRP) method describes an arm by what it looks like at
# q = 0: for each joint k its axis u_k0 and the body vector b_k0 to the next joint, all in
# the base frame. Every other pose follows by turning those vectors. In this notebook you
# build the PUMA's pose by hand, one joint rotation at a time, with Euler-Rodrigues
# parameters, and check it against the toolkit (`zrp`) and an independent engine (MuJoCo).
#
# Run the cells top to bottom (Shift+Enter). Everything here is the project's public API.

# %%
import imageio_ffmpeg
import mediapy
import mujoco
import numpy as np

import mjcf
import sim
import zrp
from zrp.rotations import er_angle, er_from_axis_angle, er_multiply, er_rotate, matrix_from_er

mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())  # mediapy's videos: imageio-ffmpeg's binary
np.set_printoptions(precision=4, suppress=True)

# %% [markdown]
# ## The model is its zero reference position
#
# The paper's Table 1 PUMA (lengths in mm). Each row: the joint axis u_k0 and the body
# vector b_k0, both at q = 0.

# %%
model = zrp.load_model("puma")
print(model.name, "-", model.n, "joints, lengths in", model.length_unit)
for k in range(model.n):
    print(f"joint {k + 1}: u = {model.axes[k]}   b = {model.bodies[k]}")
print("end effector: b =", model.bodies[model.n], " u_a =", model.end_effector.axial,
      " u_t =", model.end_effector.transverse)

# %% [markdown]
# ## Euler-Rodrigues parameters: a rotation in four numbers
#
# A rotation by angle q about the unit axis u has the parameters (eq 6)
# e0 = cos(q/2), (e1, e2, e3) = u sin(q/2). They have unit norm, and two rotations compose
# by eqs (4)-(5) (`er_multiply`), exactly as their matrices multiply.

# %%
e_a = er_from_axis_angle([0, 0, 1], np.radians(90))
e_b = er_from_axis_angle([1, 0, 0], np.radians(30))
print("e_a =", e_a, " |e_a| =", np.linalg.norm(e_a))
both = er_multiply(e_a, e_b)                    # first e_b, then e_a
print("composed:", both, " angle:", np.degrees(er_angle(both)), "deg")
print("same as the matrix product:",
      np.allclose(matrix_from_er(both), matrix_from_er(e_a) @ matrix_from_er(e_b)))
print("rotating x by e_a gives", er_rotate(e_a, [1.0, 0.0, 0.0]))

# %% [markdown]
# ## Forward kinematics by hand (eqs 1-2)
#
# R_k composes the rotations of joints 1..k about their *zero-reference* axes. Then the
# current body vector is b_k = R_{k-1} b_k0 and the tool point is the sum of the b_k.
# Try your own joint values in `q_deg`.

# %%
q_deg = np.array([10.0, -20.0, 30.0, 5.0, 45.0, 15.0])   # try your own
q = np.radians(q_deg)


def tool_point_by_hand(model: zrp.Manipulator, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    e = np.array([1.0, 0.0, 0.0, 0.0])                   # R_0 = I
    p = np.zeros(3)
    for k in range(model.n):
        p += er_rotate(e, model.bodies[k])              # b_k = R_{k-1} b_k0
        e = er_multiply(e, er_from_axis_angle(model.axes[k], q[k]))
    return p + er_rotate(e, model.bodies[model.n]), e  # the end effector's body vector


p_hand, e_hand = tool_point_by_hand(model, q)
p_zrp, e_zrp = zrp.end_effector_pose(model, q)
print("by hand :", p_hand, e_hand)
print("zrp     :", p_zrp, e_zrp)
print("largest difference (mm):", np.abs(p_hand - p_zrp).max())

# %% [markdown]
# ## The Jacobian, eq (7), against finite differences
#
# Column k of J is [u_k; u_k x (p - p_k)] for a revolute joint: rows 0-2 the hand's angular
# velocity, rows 3-5 the tool point's velocity. Nudge one joint and compare.

# %%
J = zrp.jacobian(model, q)
h = 1e-6
fd = np.stack([(zrp.end_effector_pose(model, q + h * np.eye(6)[k])[0] - p_zrp) / h
               for k in range(6)], axis=1)
print("position rows of J:\n", J[3:])
print("largest difference to finite differences (mm/rad):", np.abs(J[3:] - fd).max())

# %% [markdown]
# ## The same arm in MuJoCo
#
# `mjcf.build` turns the model into a MuJoCo model; MuJoCo computes the tool point with its
# own kinematics. The two agree to rounding. Left: the zero reference position; right: your
# `q_deg`.

# %%
arm = mjcf.build(model, mjcf.MJCFOptions(offscreen_size=(480, 360)))
site = sim.kinematic_playback(arm, q)
print("MuJoCo tool point (mm):", site.position[0],
      " difference to zrp (mm):", np.abs(site.position[0] - p_zrp).max())

data = mujoco.MjData(arm.model)
mujoco.mj_kinematics(arm.model, data)
centre = data.xpos[1:].mean(axis=0)          # the camera looks at the middle of the bodies (m)
images = {}
with sim.OffscreenRenderer(arm.model, 480, 360) as r:
    r.look_at(centre, 1.9, azimuth=135.0, elevation=-10.0)
    for title, qq in (("q = 0 (zero reference)", np.zeros(6)), (f"q = {q_deg}", q)):
        data.qpos[arm.qpos_adr] = arm.qpos(qq)
        mujoco.mj_kinematics(arm.model, data)
        images[title] = r.render_image(data)
mediapy.show_images(images, height=270)

# %% [markdown]
# ## Turn one joint
#
# A short video: joint 2 turns from 0 to 60 deg while the others stay at your `q_deg`. The
# tool point printed on the way is the ZRP one.

# %%
frames = []
with sim.OffscreenRenderer(arm.model, 480, 360) as r:
    r.look_at(centre, 1.9, azimuth=135.0, elevation=-10.0)
    for a in np.linspace(0.0, np.radians(60.0), 30):
        qq = q.copy()
        qq[1] = a
        data.qpos[arm.qpos_adr] = arm.qpos(qq)
        mujoco.mj_kinematics(arm.model, data)
        frames.append(r.render_image(data))
mediapy.show_video(frames, fps=15, height=270)
print("tool point at q2 = 60 deg (mm):",
      zrp.end_effector_pose(model, np.r_[q[0], np.radians(60.0), q[2:]])[0])

# %% [markdown]
# ## Try this
#
# * Put q_4 = q_6 = 90 deg and q_5 = 0: joints 4 and 6 are then aligned. What does the
#   Jacobian's rank tell you (`np.linalg.matrix_rank(J)`)?
# * Compose the six joint rotations in the other order. Which tool point do you get, and
#   why is the ZRP order (about the zero-reference axes, R_k = R_{k-1} e_k) the right one?
