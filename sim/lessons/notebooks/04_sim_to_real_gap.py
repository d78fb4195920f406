# %% [markdown]
# # 4. The sim-to-real gap: measure, diagnose, compensate
#
# A model is never the robot. Here the "real" robot is a MuJoCo simulation with effects the
# nominal model does not know (hidden in the next cell: do not read it yet). You do what a
# calibration engineer does with a laser tracker: measure reflectors on the tool at many
# poses, compare with the model, let the diagnosis name what is missing, then compensate
# the robot's commands and measure again.

# %%
import tempfile
import warnings
from pathlib import Path

import imageio_ffmpeg
import matplotlib.pyplot as plt
import mediapy
import numpy as np

# tqdm.auto (the measurement's progress bars) asks for ipywidgets in a notebook; the plain
# text bar is fine, and the bars are off below anyway
warnings.filterwarnings("ignore", message="IProgress not found")

import mjcf
import sim
import zrp
from mjcf.gravity import gravity_torques
from sim.studies.compensation_check import compensate_and_measure
from zrp.calibration import CalibrationOptions, calibrate
from zrp.gap.report import verdict_text

mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())
model = zrp.load_model("puma")

# %% [markdown]
# ## The sealed envelope (the teacher may change it; students read it at the end)

# %%
hidden = sim.HiddenEffects(joint_offset={3: 8e-4},            # encoder zero of joint 3, rad
                           link_length={4: (0.0, 0.0, 0.3)},  # body 4 longer by 0.3 mm
                           backlash={2: 8e-4})                # free play in joint 2, rad
robot = sim.RealRobot(model, hidden)

# %% [markdown]
# ## Measure
#
# 120 random reachable poses, three reflectors on the tool, a tracker with 0.02 mm noise
# per coordinate placed somewhere in the cell (its frame is unknown too: the diagnosis
# registers it). The robot moves straight from pose to pose, so each joint approaches from
# the side the order gives.

# %%
rng = np.random.default_rng(0)
tracker = sim.Instrument(noise_sigma=0.02)
run = sim.measure(robot, zrp.reachable_poses(model, 120, rng), tracker, rng,
                  sim.Procedure(approach="order"))
meas = run.measurements
print(len(meas.xyz), "tracker readings of", len(set(meas.point)), "reflectors")

# %% [markdown]
# ## Diagnose
#
# The diagnosis registers the tracker frame and the reflectors, then adds the effect that
# best explains poses it did *not* fit (withheld), one at a time, while it helps. It uses the
# nominal gravity torques (from the MuJoCo model of the nominal arm) so that effects driven
# by load can be told from geometric ones.

# %%
work = Path(tempfile.mkdtemp())
xml = mjcf.save_mjcf(mjcf.build(model, mjcf.MJCFOptions(inertia="puma560", visuals=False,
                                                        floor=False)), work / "nominal.xml")
with warnings.catch_warnings():
    warnings.simplefilter("ignore")   # the diagnosis's warnings are in diag.warnings
    # the one calibration recipe (as `zrp calibrate`): diagnose, then the calibrated robot
    calibration = calibrate(model, meas, options=CalibrationOptions(
        gravity_torque=gravity_torques(xml, meas.q_pose), seed=0))
diag = calibration.diagnosis
print(verdict_text(diag))

labels = ["nominal\n(registered)"] + [f"+ {s.effect}\njoints {list(s.joints)}"
                                      for s in diag.steps]
rms = [diag.nominal.rms] + [s.withheld.rms for s in diag.steps]
fig, ax = plt.subplots(figsize=(8, 3.5))
ax.bar(range(len(rms)), rms, color=["tab:gray"] + ["tab:green"] * (len(rms) - 1))
ax.axhline(diag.noise_floor.rms, color="tab:red", ls="--", label="noise floor")
ax.set_xticks(range(len(rms)), labels, fontsize=8)
ax.set_ylabel("withheld RMS error (mm)")
ax.legend()
plt.show()

# %% [markdown]
# ## What the calibration learned about the geometry
#
# The calibrated robot taken out of the diagnosis has its own geometry. Drawn along the
# paper's circle beside the nominal arm (errors magnified), it shows where the identified
# robot differs from the drawing.

# %%
cal = calibration.robot
path = zrp.circle_joint_path(model, steps=60)
frames = list(sim.video_frames(
    [sim.VideoSegment(model, cal.model, path.t, path.q, "identified geometry")],
    title="calibrated vs nominal",
    options=sim.VideoOptions(width=520, height=400, fps=15, seconds=3.0)))
mediapy.show_video(frames, fps=15, height=320)

# %% [markdown]
# ## Compensate and measure again
#
# Fresh targets (the circle and random poses) that the program was written for. First the
# program as it is, then the commands compensated with the calibrated robot; the same
# tracker measures both.

# %%
check = compensate_and_measure(robot, tracker, calibration, xml, rng, n_random=30,
                               n_circle=24)
s = check.summary()
print(f"RMS error before {s['rms_before']:.3f} mm, after {s['rms_after']:.3f} mm "
      f"(tracker noise {s['noise_rms']:.3f} mm)")
fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(check.error_before, "o", label="program as it is")
ax.plot(check.error_after, "o", label="compensated")
ax.axhline(check.noise_rms, color="tab:red", ls="--", label="tracker noise (RMS)")
ax.set_xlabel("target")
ax.set_ylabel("|measured - target| (mm)")
ax.legend()
plt.show()

# %% [markdown]
# ## Open the envelope
#
# Compare what was hidden with what the diagnosis named. Did it find every effect, on the
# right joint? Where it says the data cannot tell two effects apart, which measurements
# would?

# %%
print("hidden:", {k: v for k, v in vars(hidden).items() if v})
print("found :", [(st.effect, list(st.joints)) for st in diag.steps])

# %% [markdown]
# ## Try this
#
# * Change the envelope (a larger backlash, an `axis_misalignment={4: (3e-4, 0.0)}`) and run
#   again. Which effects are hard to tell apart?
# * Measure 40 poses instead of 120: what happens to the diagnosis and to the compensation?
#
# ## Next: the dynamic gap
#
# Notebook 5 (`05_dynamic_gap.py`) puts the robot in motion: where the model's torques
# miss (friction, rotor inertia, a payload) and how the corrected MJCF moves like the arm.
