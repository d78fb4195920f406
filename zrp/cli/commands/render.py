"""``zrp render``: MuJoCo videos of the nominal and perturbed PUMA drawing the 125 mm circle."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.options import (
    MAX_FPS,
    MAX_HEIGHT,
    MAX_SECONDS,
    MAX_WIDTH,
    PERCENT,
    add_progress,
    draw_bar,
    real,
    whole,
)
from zrp.output import OutputDir, claim_generated

if TYPE_CHECKING:
    from sim import VideoOptions
    from zrp.paper.scenes import Scene

DEFAULT_OUT = "renders"


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
    p.add_argument("--xi", type=PERCENT, default=0.1, help="perturbation in percent (default 0.1)")
    p.add_argument("--sweep", action="store_true",
                   help="also render the teaching sweep over xi = 0, 0.02, 0.05, 0.07, 0.1 %%")
    p.add_argument("--levels", nargs="+", type=PERCENT, default=None, metavar="PCT",
                   help="levels of the sweep (default the paper's)")
    p.add_argument("--steps", type=whole(2, 100_000),
                   default=360, help="inverse-kinematics steps (360)")
    out = p.add_argument("--out", default=None, metavar="DIR",
                   help=f"output folder (default {DEFAULT_OUT}/, generated output whose videos "
                        "are replaced; in any other folder an existing video needs --force). "
                        "One run at a time per folder: a second run into it is refused")
    p.add_argument("--force", action="store_true",
                   help="replace existing videos in --out (checked before rendering)")
    p.add_argument("--width", type=whole(16, MAX_WIDTH), default=640,
                   help=f"pixels, 16 to {MAX_WIDTH} (default 640)")
    p.add_argument("--height", type=whole(16, MAX_HEIGHT), default=480,
                   help=f"pixels, 16 to {MAX_HEIGHT} (default 480)")
    p.add_argument("--fps", type=whole(1, MAX_FPS), default=30,
                   help=f"frames per second, 1 to {MAX_FPS} (default 30)")
    p.add_argument("--seconds", type=real(0.0, MAX_SECONDS, open_lo=True, unit="s"), default=None,
                   help="video length (default: the trajectory's duration; 3 s per sweep level)")
    p.add_argument("--magnify", type=real(0.0, 1e9, open_lo=True), default=None,
                   help="deviation magnification (default: one round factor per parameter, "
                        "the same for the video and the sweep)")
    p.add_argument("--format", choices=("auto", "mp4", "gif"), default="auto")
    p.add_argument("--backend", default=None, help="egl or osmesa (default: MUJOCO_GL, else "
                   "the first that works)")
    p.add_argument("--no-dynamics", action="store_true",
                   help="skip the dynamic playback (PD servos under gravity, PUMA 560 inertias)")
    progress = add_progress(p)
    deprecated_alias(p, "--out-dir", out)
    deprecated_alias(p, "--quiet", progress, "--no-progress")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run)


def _result(r: Any) -> dict[str, Any]:
    return {"path": str(r.path), "frames": r.frames, "wall_seconds": r.wall_seconds,
            "magnify": r.magnify, "backend": r.backend,
            "segments": [{"label": lab.replace("\n", "; "), "max_delta_p_mm": dp,
                          "max_delta_R_eq15": dr, "max_theta_rad": th}
                         for lab, dp, dr, th in zip(r.labels, r.max_delta_p, r.max_delta_r,
                                                    r.max_theta, strict=True)]}


def _videos(args: argparse.Namespace, video_options: type[VideoOptions]
            ) -> list[tuple[Scene, VideoOptions]]:
    """The paper video's scene and options, and the teaching sweep's under ``--sweep``."""
    from zrp.paper.scenes import (  # on use: keeps --help quick
        PAPER_LEVELS,
        paper_video_scene,
        teaching_sweep_scene,
    )

    opts = video_options(width=args.width, height=args.height, fps=args.fps,
                         seconds=args.seconds, magnify=args.magnify, format=args.format,
                         backend=args.backend)
    scene = paper_video_scene(args.parameter, args.xi, steps=args.steps)
    # one magnification for every video of the parameter (the scene's), unless --magnify
    opts = replace(opts, magnify=args.magnify or scene.magnify)
    videos: list[tuple[Scene, VideoOptions]] = [(scene, opts)]
    if args.sweep:
        levels = tuple(args.levels) if args.levels else PAPER_LEVELS
        videos.append((teaching_sweep_scene(args.parameter, levels, steps=args.steps),
                       replace(opts, seconds=args.seconds or 3.0)))
    return videos


def _payload(results: list[Any], checks: list[Any], dyn: Any, seg: Any) -> dict[str, Any]:
    payload: dict[str, Any] = {
        "videos": [_result(r) for r in results],
        "consistency": [{"model": c.model_name, "max_position_error_mm": c.max_position_error_mm,
                         "max_orientation_error_rad": c.max_orientation_error,
                         "passed": c.passed()} for c in checks],
    }
    if dyn is not None:
        payload["dynamic_playback"] = {
            "model": seg.perturbed.name, "inertia": dyn.options.inertia, "kp": dyn.options.kp,
            "kv": dyn.options.kv, "max_tracking_error_mm": dyn.max_tracking_error,
            "rms_tracking_error_mm": dyn.rms_tracking_error,
            "max_geometric_delta_p_mm": results[0].max_delta_p[0]}
    return payload


def _text(results: list[Any], checks: list[Any], dyn: Any) -> str:
    lines = [r.summary() for r in results]
    lines += ["MuJoCo vs ZRP direct kinematics: " + c.summary() for c in checks]
    if dyn is not None:
        lines.append(f"perturbed arm, {dyn.summary()} (geometric delta_p max "
                     f"{results[0].max_delta_p[0]:.4g} mm)")
    return "\n".join(lines)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo (+0.1 s measured) and must see --backend before it creates a GL
    # context: imported when this command runs, not for every `zrp`.
    import sim

    videos = _videos(args, sim.VideoOptions)
    names = [sim.video_path(scene.file_name, o).name for scene, o in videos]
    overwrite = args.force or (args.out is None and claim_generated(DEFAULT_OUT))
    with OutputDir(Path(args.out or DEFAULT_OUT), overwrite=overwrite, names=names) as out:
        seg = videos[0][0].segments[0]
        checks = [sim.consistency_check(m, seg.q) for m in (seg.nominal, seg.perturbed)]
        dyn = None if args.no_dynamics else sim.dynamic_playback(seg.perturbed, seg.t, seg.q)
        results = [sim.render_video(scene.segments, out.root / name, title=scene.title,
                                    options=o, overwrite=overwrite, progress=draw_bar(args))
                   for (scene, o), name in zip(videos, names, strict=True)]
    emit(args, _payload(results, checks, dyn, seg), _text(results, checks, dyn))
    return 0
