# %% [markdown]
# # 5. The dynamic gap: where the model's torques miss
#
# Notebook 4 asked where the *tool* is. Here the arm moves, and the question is the
# *torques*: along a motion, does the MuJoCo model ask for the torques the real arm needs?
# Friction, rotor inertia (armature) and a payload nobody declared all make it miss.
#
# The "real" arm is again a simulation with effects its model lacks (the next cell hides
# them). It follows a periodic command with a joint servo and logs what every arm logs:
# joint positions, velocities and torques. You compare the log with the model's inverse
# dynamics, let the diagnosis name the effects, write them into the MJCF and re-simulate.

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import mediapy
import mujoco
import numpy as np

from mjcf.corrected import write_corrected_mjcf
from mjcf.inverse import inverse_dynamics
from mjcf.tracking import SampledCommand, tracking_gap
from sim.studies.dynamics.arms import BENCH_ARMS
from sim.studies.dynamics.scenarios import scenario_command
from sim.studies.dynamics.truth import HiddenDynamics, Servo, run_servo, simulate
from zrp.gap.dynamics import derive_states, load_torque_log, write_torque_log
from zrp.gap.dynamics.diagnosis import diagnose_dynamics


def show(fig: plt.Figure) -> None:
    """A matplotlib figure shown inline as an image by mediapy (and closed)."""
    fig.canvas.draw()
    mediapy.show_image(np.asarray(fig.canvas.buffer_rgba())[..., :3])
    plt.close(fig)


bench = BENCH_ARMS["puma"]   # the PUMA 560 with its literature link inertias
arm = bench.load()           # the nominal model: what the diagnosis knows
print(arm.name, "joints", arm.joint_names)
print("link masses (kg)", [f"{m:.3g}" for m in arm.model.body_mass[arm.moving_bodies()]])

# %% [markdown]
# ## The sealed envelope (the teacher may change it; students read it at the end)

# %%
n = arm.n
hidden = HiddenDynamics(
    armature=np.array([0.3, 0, 0, 0, 0, 0]),   # rotor inertia of joint 1, kg m^2
    coulomb=np.array([0, 3.0, 0, 0, 0, 0]),    # dry friction of joint 2, N m
    viscous=np.array([0, 0, 4.0, 0, 0, 0]),    # viscous friction of joint 3, N m s/rad
    payload_kg=1.0, payload_offset_m=np.array([0.0, 0.0, 0.02]))   # a gripper, undeclared

# %% [markdown]
# ## Run the arm and log it
#
# A periodic command (five Fourier harmonics of 0.1 Hz about a posture, starting and
# ending at rest) excites every joint. The servo is what a robot controller does: the
# *nominal* model's torques along the command (feed-forward) plus PD feedback tuned for
# 4 Hz. The log: 10 s at 1 kHz, torque noise 0.05 N m (0.09 on joint 2), encoder noise
# 10 urad. It goes through the same CSV file a real log would (units in the header).

# %%
command = scenario_command(bench.q0_array, bench.amplitude_rad, seed=5)
real = simulate(arm, hidden, command, 10.0, noise_nm=np.array([0.05, 0.09, 0.05, 0.05,
                                                                0.05, 0.05]), seed=1)
work = Path(tempfile.mkdtemp())
csv = write_torque_log(real, work / "log.csv")
print(csv.read_text().splitlines()[0][:120], "...")
log = load_torque_log(csv)
print(f"{log.n_samples} samples at {1 / log.dt:.0f} Hz, {log.n_joints} joints")

# %% [markdown]
# ## Where the model's torques miss
#
# The model's torques along the log are MuJoCo's inverse dynamics, tau = M(q) qdd +
# c(q, qd) + g(q) (`mj_inverse`; eq. R2 of `zrp.gap.dynamics.inertia` writes it linear in the
# link inertias), at the logged positions with velocities and
# accelerations from a zero-phase Savitzky-Golay filter (differentiating raw encoder
# readings twice would multiply their noise by 1/dt^2, a million at 1 kHz). The residual,
# measured minus model, plotted against each joint's velocity is where an engineer looks
# first:
#
# * a **step** at zero velocity (the sign flips when the joint reverses): Coulomb friction;
# * a **slope** through the origin: viscous friction;
# * a **band** that does not depend on velocity: something driven by acceleration
#   (armature) or by the posture (a payload's weight): plot against those instead.

# %%
states = derive_states(log)
every = slice(None, None, 10)   # 100 Hz is plenty for plots and for mj_inverse here
tau_model = inverse_dynamics(arm.model, states.q[every], states.qd[every], states.qdd[every])
residual = log.tau[every] - tau_model
fig, axes = plt.subplots(2, 3, figsize=(11, 5.5), sharex=True)
for k, ax in enumerate(axes.flat):
    ax.plot(states.qd[every, k], residual[:, k], ".", ms=2, color="tab:red")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_title(f"joint {k + 1}: RMS {np.sqrt(np.mean(residual[:, k] ** 2)):.2f} N m")
    if k >= 3:
        ax.set_xlabel("joint velocity (rad/s)")
    if k % 3 == 0:
        ax.set_ylabel("measured - model (N m)")
fig.suptitle("Torque residual of the nominal model against velocity")
fig.tight_layout()
show(fig)

# %% [markdown]
# Before reading on: which joints have a step, which a slope, which a band? Joint 2 carries
# the arm's weight; what would an extra mass at the tool do to it, and to joint 5?

# %% [markdown]
# ## Diagnose
#
# The diagnosis sees only the nominal model and the log. It estimates each joint's torque
# noise (the floor no model can go below), then adds the candidate effect (friction laws,
# armature, a torque sensor's offset or gain, a payload, the link inertias) that best
# predicts the torques of time segments it did *not* fit on (withheld), one at a time,
# while it helps. Each effect is linear in its parameters, so each step is a least-squares
# fit; the intervals are 95 %.

# %%
diag = diagnose_dynamics(arm, log)
for e in diag.effects:
    print(e.label)
    for name, p in e.params.items():
        print(f"    {name} = {p.value:.3g} {p.unit}  [{p.low:.3g}, {p.high:.3g}]")
print("\ncannot tell apart along this log:")
for line in diag.cannot_tell:
    print("   ", line)

x = np.arange(n)
fig, ax = plt.subplots(figsize=(8, 3.5))
ax.bar(x - 0.2, diag.rms_before, 0.4, color="tab:red", label="nominal model")
ax.bar(x + 0.2, diag.rms_after, 0.4, color="tab:blue", label="corrected (withheld)")
ax.plot(x, diag.noise_nm, "k_", ms=20, mew=2, label="torque noise floor")
ax.set_yscale("log")
ax.set_xticks(x, [f"joint {k + 1}" for k in x])
ax.set_ylabel("torque RMS error (N m)")
ax.legend()
show(fig)
for k in range(n):
    print(f"joint {k + 1}: {diag.rms_before[k]:6.3f} -> {diag.rms_after[k]:6.3f} N m, "
          f"{diag.rms_after[k] / diag.noise_nm[k]:.2f} x the noise floor "
          f"{diag.noise_nm[k]:.3f}")

# %% [markdown]
# The withheld residual after the correction, against velocity: what is left is noise,
# except on joint 2 near zero speed. The real arm's dry friction is MuJoCo's
# `frictionloss` constraint, which holds the joint still at a reversal (stiction); the
# diagnosis's smooth Coulomb law cannot take that instant. Its table of residuals per
# regime (the report of `zrp diagnose-dynamics` has it for every joint) shows where.

# %%
s = diag.samples
fig, axes = plt.subplots(2, 3, figsize=(11, 5.5), sharex=True)
for k, ax in enumerate(axes.flat):
    ax.plot(s.qd[:, k], s.before[:, k], ".", ms=2, color="tab:red", label="before")
    ax.plot(s.qd[:, k], s.after[:, k], ".", ms=2, color="tab:blue", label="after")
    ax.set_title(f"joint {k + 1}")
    if k >= 3:
        ax.set_xlabel("joint velocity (rad/s)")
    if k % 3 == 0:
        ax.set_ylabel("measured - model (N m)")
axes.flat[0].legend(markerscale=5)
fig.tight_layout()
show(fig)
print("joint 2, RMS residual per regime (N m):")
for regime, before in diag.regimes["before"].items():
    after = diag.regimes["after"][regime]
    if before[1] is not None:
        print(f"    {regime:15s} {before[1]:6.3f} -> {after[1]:6.3f}")

# %% [markdown]
# ## The corrected MJCF
#
# The effects MJCF has a place for are written in: Coulomb friction as `frictionloss`,
# viscous friction as `damping`, rotor inertia as `armature`, the payload as a body at the
# tool. It loads in MuJoCo as is.

# %%
xml = write_corrected_mjcf(arm, diag, work / "corrected.xml")
corrected = mujoco.MjModel.from_xml_path(str(xml))
for field in ("dof_frictionloss", "dof_damping", "dof_armature"):
    print(f"{field:17s} nominal {getattr(arm.model, field).round(3)}")
    print(f"{'':17s} corrected {getattr(corrected, field).round(3)}")
print("payload body:", mujoco.mj_id2name(corrected, mujoco.mjtObj.mjOBJ_BODY,
                                          corrected.nbody - 1),
      f"{corrected.body_mass[-1]:.3f} kg")

# %% [markdown]
# ## Re-simulate: does the corrected model move like the arm?
#
# The logged command drives each model through the *same* servo (its feed-forward still
# from the nominal model, as on the real controller). The nominal model has no friction
# and no payload, so the servo tracks it almost perfectly; the real arm lagged. A model
# that is right lags the same way: its simulated positions follow the logged ones.
#
# Why a plot and not a video: the gap is a few milliradians (millimetres at the tool).
# Drawn to scale the two arms coincide; magnified, a video would show no more than the
# error traces below, and rendering it costs more than the rest of the notebook.

# %%
servo = Servo.tuned(arm, log.qc[0])
cmd = SampledCommand(log.t, log.qc)
gap_nominal = tracking_gap(arm.model, arm.model, log, servo, cmd)
gap_corrected = tracking_gap(corrected, arm.model, log, servo, cmd)
for k in range(n):
    print(f"joint {k + 1}: tracking gap {1e3 * gap_nominal[k]:6.3f} -> "
          f"{1e3 * gap_corrected[k]:6.3f} mrad")

seconds = 4.0   # the first seconds are enough to see it
nom = run_servo(arm.model, arm.model, servo, cmd, seconds)
cor = run_servo(corrected, arm.model, servo, cmd, seconds)
m = nom.t.size
fig, axes = plt.subplots(1, 3, figsize=(12, 3.5))
for ax, k in zip(axes, (1, 2, 4), strict=True):   # joints 2, 3 and 5
    ax.plot(log.t[:m], 1e3 * (log.q[:m, k] - log.qc[:m, k]), color="k", lw=3, alpha=0.4,
            label="real arm (log)")
    ax.plot(nom.t, 1e3 * (nom.q[:, k] - nom.qc[:, k]), color="tab:red", label="nominal model")
    ax.plot(cor.t, 1e3 * (cor.q[:, k] - cor.qc[:, k]), "--", color="tab:blue",
            label="corrected model")
    ax.set_title(f"joint {k + 1}: position - command")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("tracking error (mrad)")
axes[0].legend()
fig.tight_layout()
show(fig)

# %% [markdown]
# ## Open the envelope
#
# Compare what was hidden with what the diagnosis named, on which joint and how large.
# Did it find everything? What did it say it could not tell apart, and why (look at what
# joint 1 carries)?

# %%
for name in ("armature", "coulomb", "viscous"):
    for k in np.flatnonzero(hidden.per_joint(name, n)):
        print(f"hidden: {name} (joint {k + 1}) {hidden.per_joint(name, n)[k]:g}")
print(f"hidden: payload {hidden.payload_kg:g} kg, offset {hidden.payload_offset_m} m")
print("found :", [e.label for e in diag.effects])

# %% [markdown]
# ## Try this
#
# * Hide a torque sensor `offset` on joint 4 instead of the friction. How can the
#   diagnosis tell an offset from Coulomb friction (what happens at a reversal)? Log 1 s
#   only: can it still? Read `diag.cannot_tell`.
# * Add a Stribeck bump (`stribeck=..., stribeck_speed=0.08`): what does MJCF have no
#   place for, and what does the corrected model then miss?
# * Log 3 s instead of 10 s: how do the intervals change?
