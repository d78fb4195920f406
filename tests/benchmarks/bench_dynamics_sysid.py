"""The dynamic gap diagnosis against ``mujoco.sysid`` on the same problem.

Problem: the Menagerie UR5e with hidden Coulomb friction on joint 2 (2 N m), viscous friction
on joint 4 (0.5 N m s/rad) and a 1 kg payload, driven by a servo along an exciting Fourier
command; 20 s logged at 1 kHz (positions, velocities, motor torques with 1 % noise).

* ``zrp`` (:func:`zrp.gap.dynamics.diagnosis.diagnose_dynamics`): inverse dynamics along the log,
  which effects among all candidates, their sizes with intervals; linear least squares.
* ``mujoco.sysid``: simulation error. The measured torques drive the model open loop
  (``motor`` actuators); the parameters are fitted so that the simulated joint positions and
  velocities follow the log, over windows of ``--window`` s each started from the logged state
  (a single 20 s open-loop rollout of a 6-joint arm under gravity drifts away). It needs the
  parameters chosen beforehand: here the three true ones (frictionloss of joint 2, damping of
  joint 4, the payload mass), a choice the dynamic gap diagnosis makes from the data.

Run: python3 tests/benchmarks/bench_dynamics_sysid.py [--window 1.0] [--windows 6] [--quick]
[--out FILE.md] [--force]   (writes renders/benchmarks/bench_dynamics_sysid.md and .json)
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np
from _report import Report, add_output_arguments, output_path

from sim.studies.dynamics.arms import BENCH_ARMS
from sim.studies.dynamics.scenarios import scenario_command
from sim.studies.dynamics.truth import HiddenDynamics, simulate
from zrp.gap.dynamics.diagnosis import diagnose_dynamics

TRUE = {"frictionloss_j2": 2.0, "damping_j4": 0.5, "payload_kg": 1.0}


def _sysid_spec(arm):
    spec = arm.spec.copy()
    for act in list(spec.actuators):
        spec.delete(act)
    for s in list(spec.sensors):
        spec.delete(s)
    spec.option.timestep = 0.001
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT
                                    | mujoco.mjtDisableBit.mjDSBL_LIMIT)
    spec.option.integrator = int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    for name in arm.joint_names:
        spec.add_actuator(name=f"m_{name}", target=name,
                          trntype=mujoco.mjtTrn.mjTRN_JOINT)
    for name in arm.joint_names:
        spec.add_sensor(name=f"p_{name}", type=mujoco.mjtSensor.mjSENS_JOINTPOS, objname=name,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT)
    for name in arm.joint_names:
        spec.add_sensor(name=f"v_{name}", type=mujoco.mjtSensor.mjSENS_JOINTVEL, objname=name,
                        objtype=mujoco.mjtObj.mjOBJ_JOINT)
    tool = spec.body(mujoco.mj_id2name(arm.model, mujoco.mjtObj.mjOBJ_BODY, arm.tool_body))
    load = tool.add_body(name="payload", pos=list(arm.tool_point))
    load.explicitinertial = True
    load.mass = 1e-6
    load.inertia = [1e-9] * 3
    return spec


def _run_sysid(arm, log, window_s: float, windows: int):
    from mujoco import sysid  # needs mujoco's "sysid" extra (checked in main)

    spec = _sysid_spec(arm)
    model = spec.compile()
    names = arm.joint_names
    params = sysid.ParameterDict()
    params.add(sysid.Parameter("frictionloss_j2", nominal=0.0, min_value=0.0, max_value=10.0,
                               modifier=lambda s, p: setattr(s.joint(names[1]), "frictionloss",
                                                             p.value[0])))
    params.add(sysid.Parameter("damping_j4", nominal=0.0, min_value=0.0, max_value=5.0,
                               modifier=lambda s, p: setattr(s.joint(names[3]), "damping",
                                                             [p.value[0], 0.0, 0.0])))
    params.add(sysid.Parameter("payload_kg", nominal=1e-6, min_value=1e-6, max_value=5.0,
                               modifier=lambda s, p: setattr(s.body("payload"), "mass",
                                                             p.value[0])))
    k = round(window_s / log.dt)
    starts = np.linspace(0, log.n_samples - k - 1, windows).astype(int)
    seqs = []
    data = mujoco.MjData(model)
    for i, s0 in enumerate(starts):
        sl = slice(s0, s0 + k)
        data.qpos[:], data.qvel[:] = log.q[s0], log.qd[s0]
        init = sysid.create_initial_state(model, data.qpos, data.qvel, data.act)
        t = log.t[sl] - log.t[s0]
        ctrl = sysid.TimeSeries(t, log.tau[sl])
        sens = sysid.TimeSeries.from_names(t, np.hstack([log.q[sl], log.qd[sl]]), model)
        seqs.append(sysid.ModelSequences("ur5e", spec, f"w{i}", init, ctrl, sens))
    residual_fn = sysid.build_residual_fn(models_sequences=seqs)
    t0 = time.perf_counter()
    opt, _ = sysid.optimize(initial_params=params, residual_fn=residual_fn, optimizer="mujoco")
    return {k: float(opt[k].value[0]) for k in TRUE}, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--window", type=float, default=1.0, help="sysid window, s")
    ap.add_argument("--windows", type=int, default=6)
    ap.add_argument("--quick", action="store_true", help="a 10 s log, 3 windows of 0.5 s")
    add_output_arguments(ap, "bench_dynamics_sysid")
    args = ap.parse_args()
    out = output_path(args)
    from mujoco import sysid

    if not hasattr(sysid, "optimize"):
        raise SystemExit("mujoco.sysid is missing its dependencies: pip install 'mujoco[sysid]'")
    seconds = 10.0 if args.quick else 20.0
    if args.quick:
        args.window, args.windows = 0.5, 3
    bench = BENCH_ARMS["ur5e"]
    arm = bench.load()
    command = scenario_command(bench.q0_array, bench.amplitude_rad, 1)
    hidden = HiddenDynamics(coulomb=np.array([0, 2.0, 0, 0, 0, 0]),
                            viscous=np.array([0, 0, 0, 0.5, 0, 0]), payload_kg=1.0)
    noise = np.array([0.05, 0.3, 0.15, 0.05, 0.02, 0.02])
    log = simulate(arm, hidden, command, seconds, noise_nm=noise, seed=2)
    t0 = time.perf_counter()
    d = diagnose_dynamics(arm, log)
    t_zrp = time.perf_counter() - t0
    zrp = {"frictionloss_j2": _value(d, "coulomb", 1), "damping_j4": _value(d, "viscous", 3),
           "payload_kg": _value(d, "payload", None, "mass")}
    fit, t_sysid = _run_sysid(arm, log, args.window, args.windows)
    report = Report("bench_dynamics_sysid", "the dynamic gap diagnosis against mujoco.sysid")
    report.table("Parameters", ["parameter", "true", "zrp diagnose-dynamics", "mujoco.sysid"],
                 [[k, v, f"{zrp[k]:.4g}", f"{fit[k]:.4g}"] for k, v in TRUE.items()])
    report.table("Cost", ["method", "wall time (s)", "effects chosen by"], [
        ["zrp", f"{t_zrp:.1f}", "the data: " + ", ".join(e.label for e in d.effects)],
        ["mujoco.sysid", f"{t_sysid:.1f}", "the user (the three true parameters given)"]])
    report.note("Setup", f"log {seconds:g} s at 1 kHz; sysid: {args.windows} windows of "
                f"{args.window:g} s, open-loop torque replay from the logged state; "
                "optimizer 'mujoco'.")
    report.write(out, args)
    print(f"wrote {out}")


def _value(d, name, joint, param=None) -> float:
    e = d.effect(name, joint)
    return float("nan") if e is None else e.params[param or name].value


if __name__ == "__main__":
    main()
