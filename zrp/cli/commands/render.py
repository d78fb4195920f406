"""``zrp render``: MuJoCo videos of the nominal and perturbed PUMA drawing the 125 mm circle."""

from __future__ import annotations

import argparse

from zrp.cli.main import emit


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "render", help="video of the nominal (ghost) and perturbed PUMA drawing the circle",
        description="Offscreen MuJoCo rendering (EGL or OSMesa; honours MUJOCO_GL) of the "
        "paper's 125 mm PUMA circle: perturbed arm, nominal ghost, desired/actual paths and "
        "deviation vectors magnified by a stated factor, delta_p / delta_R text and a live "
        "delta_p plot. --sweep adds the teaching demo over the paper's perturbation levels. "
        "Also runs the MuJoCo-vs-ZRP consistency check on the trajectory.")
    p.add_argument("--parameter", default="JE2",
                   help="perturbed parameter, LE<k> or JE<k> (default JE2)")
    p.add_argument("--xi", type=float, default=0.1, help="perturbation in percent (default 0.1)")
    p.add_argument("--sweep", action="store_true",
                   help="also render the teaching sweep over xi = 0, 0.02, 0.05, 0.07, 0.1 %%")
    p.add_argument("--levels", nargs="+", type=float, default=None, metavar="PCT",
                   help="levels of the sweep (default the paper's)")
    p.add_argument("--steps", type=int, default=360, help="inverse-kinematics steps (360)")
    p.add_argument("--out-dir", default="renders", help="output folder (default renders/)")
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    p.add_argument("--fps", type=int, default=30)
    p.add_argument("--seconds", type=float, default=None,
                   help="video length (default: the trajectory's duration; 3 s per sweep level)")
    p.add_argument("--magnify", type=float, default=None,
                   help="deviation magnification (default: automatic round factor)")
    p.add_argument("--format", choices=("auto", "mp4", "gif"), default="auto")
    p.add_argument("--backend", default=None, help="egl or osmesa (default: MUJOCO_GL, else "
                   "the first that works)")
    p.add_argument("--no-dynamics", action="store_true",
                   help="skip the dynamic playback (PD servos under gravity, PUMA 560 inertias)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import sim
    from zrp.manufacturing.perturb import Perturbation
    from zrp.model.files import load_model
    from zrp.paper.scenario import puma_circle_ik

    opts = sim.VideoOptions(width=args.width, height=args.height, fps=args.fps,
                            seconds=args.seconds, magnify=args.magnify, format=args.format,
                            backend=args.backend)
    ik = puma_circle_ik(steps=args.steps)
    nominal = load_model("puma")
    perturbed = Perturbation.single(args.parameter, args.xi).apply(nominal)
    checks = [sim.consistency_check(m, ik.q) for m in (nominal, perturbed)]
    dyn = None if args.no_dynamics else sim.dynamic_playback(perturbed, ik.t, ik.q)
    results = [sim.render_paper_video(args.out_dir, parameter=args.parameter, xi_percent=args.xi,
                                      steps=args.steps, options=opts, progress=not args.quiet)]
    if args.sweep:
        from dataclasses import replace

        sweep_opts = replace(opts, seconds=None)
        results.append(sim.render_teaching_sweep(
            args.out_dir, parameter=args.parameter,
            levels=tuple(args.levels) if args.levels else sim.PAPER_LEVELS,
            seconds_per_level=args.seconds or 3.0, steps=args.steps, options=sweep_opts,
            progress=not args.quiet))
    payload = {
        "videos": [{"path": str(r.path), "frames": r.frames, "wall_seconds": r.wall_seconds,
                    "magnify": r.magnify, "backend": r.backend,
                    "segments": [{"label": lab.replace("\n", "; "), "max_delta_p_mm": dp,
                                  "max_delta_R_eq15": dr, "max_theta_rad": th}
                                 for lab, dp, dr, th in zip(r.labels, r.max_delta_p,
                                                            r.max_delta_r, r.max_theta,
                                                            strict=True)]}
                   for r in results],
        "consistency": [{"model": c.model_name, "max_position_error_mm": c.max_position_error_mm,
                         "max_orientation_error_rad": c.max_orientation_error,
                         "passed": c.passed()} for c in checks],
    }
    if dyn is not None:
        payload["dynamic_playback"] = {
            "model": perturbed.name, "inertia": dyn.options.inertia, "kp": dyn.options.kp,
            "kv": dyn.options.kv, "max_tracking_error_mm": dyn.max_tracking_error,
            "rms_tracking_error_mm": dyn.rms_tracking_error,
            "max_geometric_delta_p_mm": results[0].max_delta_p[0]}
    text = "\n".join([r.summary() for r in results]
                     + ["MuJoCo vs ZRP direct kinematics: " + c.summary() for c in checks]
                     + ([f"perturbed arm, {dyn.summary()} (geometric delta_p max "
                         f"{results[0].max_delta_p[0]:.4g} mm)"] if dyn is not None else []))
    emit(args, payload, text)
    return 0
