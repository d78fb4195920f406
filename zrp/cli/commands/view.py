"""``zrp view``: MuJoCo's interactive viewer on the nominal or a perturbed PUMA playing the
paper's circle (where a display exists; otherwise a clear message, exit code 2)."""

from __future__ import annotations

import argparse

from zrp.cli.app import emit
from zrp.cli.options import MAX_STEPS, PERCENT, whole


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "view", help="interactive MuJoCo viewer: the PUMA playing the circle (needs a display)",
        description="Opens MuJoCo's viewer on the Table 1 PUMA, nominal or with one parameter "
        "perturbed (--parameter, --xi), playing the 125 mm circle in a loop with the desired "
        "path (green) and the actual path magnified (magenta). Without a display it says so "
        "and exits with code 2; `zrp render` makes an offscreen video instead.")
    p.add_argument("--parameter", default="JE2", help="perturbed parameter (default JE2)")
    p.add_argument("--xi", type=PERCENT, default=0.1,
                   help="perturbation in percent (default 0.1; 0 for the nominal arm)")
    p.add_argument("--steps", type=whole(1, MAX_STEPS), default=360,
                   help="inverse-kinematics steps (360)")
    p.add_argument("--loops", type=whole(1), default=None, help="stop after this many rounds")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo (and the viewer GLFW): only when this command runs
    import sim
    from zrp.paper.scenes import paper_video_scene  # on use: keeps --help quick

    ok, why = sim.display_status()
    if not ok:
        raise sim.DisplayUnavailableError(
            f"zrp view: {why}; use `zrp render` (an offscreen video) instead, or run where a "
            "display exists (a desktop session, `xvfb-run zrp view`, ssh -X)")
    scene = paper_video_scene(args.parameter, args.xi, steps=args.steps)
    seg = scene.segments[0]
    sim.view_path(seg.nominal, seg.perturbed, seg.t, seg.q, magnify=scene.magnify or 1.0,
                  loops=args.loops)
    emit(args, {"viewer": "closed", "display": why}, f"viewer closed ({why})")
    return 0
