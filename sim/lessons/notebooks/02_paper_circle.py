# %% [markdown]
# # 2. The paper's circle: one perturbed link, one perturbed axis
#
# The paper's example: the Table 1 PUMA draws a 125 mm circle in 4 s. Its *nominal* joint
# values q(t) come from the inverse kinematics of the perfect arm. A real arm is built with
# small errors: a link a little long (LE_k: body vector b_k scaled), a joint axis a little
# tilted (JE_k). Driven with the same q(t), the real tool point leaves the circle. How far,
# and how does it change along the circle?
#
# The perturbation xi is in percent (eqs 8-12): xi = 0.1 % scales a link by 1.001 and tilts
# an axis by alpha = atan(sqrt(2) xi / (1 + xi)), about 1.4 mrad.

# %%
import tempfile
from pathlib import Path

import imageio.v3 as iio
import imageio_ffmpeg
import matplotlib.pyplot as plt
import mediapy
import numpy as np

import sim
import zrp

mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())  # mediapy's videos: imageio-ffmpeg's binary

# %% [markdown]
# ## The nominal circle
#
# `zrp.puma_circle_ik` integrates the inverse kinematics along the circle (eq 7 and a
# position correction). Its summary says how well the perfect arm follows the circle.

# %%
ik = zrp.puma_circle_ik(steps=240)
model = zrp.load_model("puma")
print({k: v for k, v in ik.summary().items() if "error" in k})
print("joint range (deg):", np.round(np.degrees(np.ptp(ik.q, axis=0)), 1))

# %% [markdown]
# ## Perturb one link, then one axis
#
# Change `LINK` and `AXIS` and run again: LE2, LE3, LE4 for links; JE1 ... JE6 for axes.

# %%
LINK, AXIS, XI = "LE3", "JE2", 0.1          # xi in percent
dev = {name: zrp.trajectory_deviation(model, zrp.Perturbation({name: XI}), ik.q, ik.t)
       for name in (LINK, AXIS)}
fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
for name, d in dev.items():
    a1.plot(d.t, d.delta_p, lw=2, label=f"{name}, xi = {XI} %")
    a2.plot(d.t, 1e3 * d.angle_rad, lw=2, label=name)
a1.set_ylabel("delta_p (mm), eq (17)")
a2.set_ylabel("error angle (mrad)")
a2.set_xlabel("time (s)")
a1.legend()
a1.set_title("the same joint values, two different arms")
for ax in (a1, a2):
    ax.grid(alpha=0.3)
plt.show()
for name, d in dev.items():
    print(f"{name}: max delta_p = {d.max_delta_p:.4f} mm, max angle = {d.max_angle_rad:.2e} rad")

# %% [markdown]
# What you see: the link error moves the tool by a constant xi ||b_3|| = 0.4318 mm and never
# turns it (the angle is exactly 0), because every joint rotation carries the longer link
# with it. The tilted axis moves *and* turns the tool, and by how much depends on how far
# joint 2 has turned from the zero reference: theta = 2 |sin(q_2 / 2)| alpha.

# %%
alpha = np.arctan(np.sqrt(2.0) * XI / 100 / (1 + XI / 100))
dq2 = ik.q[:, 1]
closed = 2 * np.abs(np.sin(dq2 / 2)) * alpha
print("JE2: measured angle vs closed form, largest difference (rad):",
      np.abs(dev["JE2"].angle_rad - closed).max() if AXIS == "JE2" else "(set AXIS = 'JE2')")

# %% [markdown]
# ## See it: nominal and perturbed side by side
#
# MuJoCo draws both arms offscreen (the same rendering the project's videos use). On the
# left the nominal arm, on the right the arm with the tilted axis; its errors and its
# deviation are magnified (the factor is printed on the frame) so that a fraction of a
# millimetre becomes visible. Green: the desired circle; magenta: the path actually drawn;
# yellow arrow: the deviation now. On the left both arms are the nominal one: they coincide,
# and the magenta path lies on the green one.

# %%
perturbed = zrp.Perturbation({AXIS: XI}).apply(model)
opts = sim.VideoOptions(width=520, height=400, fps=15, seconds=4.0, magnify=100.0, plot=False)
nominal_frames = list(sim.video_frames([sim.VideoSegment(model, model, ik.t, ik.q, "nominal")],
                                       title="nominal", options=opts))
perturbed_frames = list(sim.video_frames(
    [sim.VideoSegment(model, perturbed, ik.t, ik.q, f"{AXIS} xi = {XI} %")],
    title="perturbed", options=opts))
mediapy.show_videos({"nominal": nominal_frames, f"{AXIS} at {XI} %": perturbed_frames},
                    fps=15, height=300)

# %% [markdown]
# ## A video file, and frames from it
#
# `sim.render_video` writes the same kind of video to an mp4 file (frames streamed to
# ffmpeg, never all in memory). imageio reads frames back from the file: here the start,
# the middle and the end of the circle.

# %%
work = Path(tempfile.mkdtemp())
res = sim.render_video([sim.VideoSegment(model, perturbed, ik.t, ik.q, f"{AXIS} {XI} %")],
                       work / "circle.mp4", title="the paper's circle", progress=False,
                       options=sim.VideoOptions(width=480, height=360, fps=10, seconds=4.0))
print(res.summary())
frames = iio.imread(res.path, plugin="FFMPEG", index=None)
print("frames read back:", frames.shape)
picks = [0, len(frames) // 2, len(frames) - 1]
mediapy.show_images({f"frame {i}": frames[i] for i in picks}, height=240)

# %% [markdown]
# ## Try this
#
# * Set `AXIS = "JE6"`. Why is its positional deviation so small on this circle (look at
#   the end effector's body vector and where joint 6's axis points)?
# * Set `XI = -0.1`. Which curves change sign, which do not, and why?
