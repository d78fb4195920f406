# %% [markdown]
# # 3. Monte Carlo and tolerance allocation
#
# Notebook 2 perturbed one parameter at a time. A real arm has *every* parameter a little
# off, each somewhere within its tolerance. Every arm built to the same drawing is a
# different arm, so the question "how accurate is this design?" has a distribution for an
# answer: draw many arms, drive each along the circle, record each one's largest deviation.
# Then turn it around: which tolerances, as loose (cheap) as possible, keep 99 % of the arms
# within a requirement?

# %%
import imageio_ffmpeg
import matplotlib.pyplot as plt
import mediapy
import numpy as np

import sim
import zrp

mediapy.set_ffmpeg(imageio_ffmpeg.get_ffmpeg_exe())
model = zrp.load_model("puma")
path = zrp.circle_joint_path(model, steps=60)   # the paper's circle, 61 samples
print(path.q.shape, "joint values along the circle")

# %% [markdown]
# ## A tolerance stack
#
# Every body-vector component within +-0.01 mm, every joint axis within +-0.05 mrad of
# tilt (uniform). `Tolerances.build` lists one tolerance per parameter.

# %%
tol = zrp.Tolerances.build(model, length=0.01, angle_rad=5e-5)
print(len(tol.names), "parameters, e.g.", dict(list(tol.as_dict().items())[:4]))

# %% [markdown]
# ## Many robots
#
# `monte_carlo` draws N robots, drives each along the nominal joint path and keeps each
# robot's largest positional deviation (and angle); `first_order=True` also evaluates the
# linearised model (the parameter Jacobian) with the same draws.

# %%
N = 20000
mc = zrp.monte_carlo(model, path.q, tol, N, rng=np.random.default_rng(0), first_order=True)
p50 = np.percentile(mc.max_delta_p, 50)
p99, ang99 = mc.percentile(99)
print(f"median {p50:.4f} mm, P99 {p99:.4f} mm (angle P99 {ang99:.2e} rad), "
      f"worst {mc.max_delta_p.max():.4f} mm")

fig, ax = plt.subplots(figsize=(8, 3.5))
ax.hist(mc.max_delta_p, bins=80, alpha=0.7, label=f"{N} robots (nonlinear)")
ax.hist(mc.first_order_delta_p, bins=80, histtype="step", color="k", label="first order")
for v, lab, ls in ((p50, "median", "--"), (p99, "P99", ":")):
    ax.axvline(v, color="tab:red", ls=ls, label=f"{lab} {v:.3f} mm")
ax.set_xlabel("max delta_p along the circle (mm)")
ax.set_ylabel("robots")
ax.legend()
plt.show()

# %% [markdown]
# ## Meet one robot of the population
#
# Draw 200 robots yourself (each parameter uniform within its tolerance), apply each draw to
# the model (`apply_parameters`) and keep the one that strays furthest from the circle. The
# video shows it beside its nominal ghost, errors and deviation magnified.

# %%
rng = np.random.default_rng(3)
draws = rng.uniform(-1.0, 1.0, (200, len(tol.values))) * tol.values
robots = [zrp.apply_parameters(model, dx)[0] for dx in draws]
worst_dp = [zrp.pose_deviation(model, r, path.q, path.t).max_delta_p for r in robots]
k = int(np.argmax(worst_dp))
print(f"robot {k}: max delta_p {worst_dp[k]:.4f} mm (population P99 {p99:.4f} mm)")
frames = list(sim.video_frames(
    [sim.VideoSegment(model, robots[k], path.t, path.q, f"robot {k} of 200")],
    title="one robot built within the tolerances",
    options=sim.VideoOptions(width=520, height=400, fps=15, seconds=4.0)))
mediapy.show_video(frames, fps=15, height=320)

# %% [markdown]
# ## How many robots are enough?
#
# The P99 estimate from the first n robots: it settles as n grows. A percentile from a
# sample has its own uncertainty; that is why the allocation below verifies its result with
# fresh draws.

# %%
ns = np.unique(np.geomspace(100, N, 25).astype(int))
est = [np.percentile(mc.max_delta_p[:n], 99) for n in ns]
fig, ax = plt.subplots(figsize=(8, 3))
ax.semilogx(ns, est, "o-")
ax.axhline(p99, color="k", ls=":", label=f"P99 of all {N}")
ax.set_xlabel("robots drawn")
ax.set_ylabel("P99 estimate (mm)")
ax.legend()
plt.show()

# %% [markdown]
# ## Tolerance allocation
#
# Require P99 of the max deviation <= 0.05 mm. Equal tolerances on everything waste money
# on parameters that barely matter. `allocate_tolerances` shapes the tolerances by each
# parameter's sensitivity along the circle (a reciprocal cost model: looser is cheaper),
# scales them to the requirement, and verifies with a fresh nonlinear Monte Carlo.

# %%
alloc = zrp.allocate_tolerances(model, path.q, rng=np.random.default_rng(1), max_delta_p=0.05,
                                percentile=99, n_search=2000, n_verify=10000)
s = alloc.summary()
print("verified:", s["verified"], f"P99 = {s['verified_p99_delta_p']:.4f} mm (required 0.05)")
print(f"looseness {s['looseness_mm']:.4f} mm vs equal tolerances "
      f"{s['baseline_equal_tolerance_looseness_mm']:.4f} mm: "
      f"x{s['looser_than_baseline_factor']:.2f} looser")

# %% [markdown]
# Which parameters got loose tolerances and which tight ones? Lengths in mm, tilts as
# mm-equivalents (tilt x 100 mm). The parameters the circle barely feels get loose
# tolerances (capped); the sensitive ones get tight ones.

# %%
eq = alloc.tolerances.equivalent_mm(alloc.angle_scale_mm)
base = alloc.baseline.equivalent_mm(alloc.angle_scale_mm)
order = np.argsort(eq)
fig, ax = plt.subplots(figsize=(9, 4))
ax.bar(range(len(eq)), eq[order], label="allocated")
ax.plot(range(len(eq)), base[order], "k_", ms=12, label="equal tolerances, same P99")
ax.set_xticks(range(len(eq)), [alloc.tolerances.names[i] for i in order], rotation=90, fontsize=7)
ax.set_yscale("log")
ax.set_ylabel("tolerance (mm or mm-equivalent)")
ax.legend()
fig.tight_layout()
plt.show()

# %% [markdown]
# ## Check it yourself
#
# A fresh population built to the allocated tolerances, and one built to the equal
# tolerances: both meet the requirement, the allocated one with much looser parts.

# %%
fresh = zrp.monte_carlo(model, path.q, alloc.tolerances, 5000, rng=np.random.default_rng(7))
equal = zrp.monte_carlo(model, path.q, alloc.baseline, 5000, rng=np.random.default_rng(7))
print(f"allocated: P99 {fresh.percentile(99)[0]:.4f} mm; "
      f"equal: P99 {equal.percentile(99)[0]:.4f} mm")
fig, ax = plt.subplots(figsize=(8, 3))
ax.hist(fresh.max_delta_p, bins=60, alpha=0.6, label="allocated tolerances")
ax.hist(equal.max_delta_p, bins=60, alpha=0.6, label="equal tolerances")
ax.axvline(0.05, color="k", ls="--", label="requirement (P99)")
ax.set_xlabel("max delta_p along the circle (mm)")
ax.legend()
plt.show()

# %% [markdown]
# ## Try this
#
# * Require an angle too (`max_angle_rad=2e-4`). Which tolerances tighten?
# * Fix the base (`fixed={"b1*": 0.0}`): a part you machine once, very precisely.
