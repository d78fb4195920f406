"""``zrp paper``: the paper's whole numerical example into renders/ (tables, figures, report).

Also renders the nominal-vs-perturbed video of the circle (the scene from
:mod:`zrp.paper.scenes`, rendered by :func:`sim.render_video`; ``--no-video`` skips it).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.commands.study import add_path_options, check_path_options, path_from_args
from zrp.cli.options import add_progress, draw_bar
from zrp.errors import InputError

if TYPE_CHECKING:
    from zrp.model.manipulator import Manipulator
from zrp.output import OutputDir, claim_generated
from zrp.paper.choices import CIRCLES

if TYPE_CHECKING:
    from zrp.paper.example import PaperExample
from zrp.paper.index import INDEX_NAME, write_index

DEFAULT_OUT = "renders"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "paper", help="reproduce the paper's numerical example (Tables 2-3, Figures 2-7)",
        description="Nominal IK of the 125 mm circle on the Table 1 PUMA, the one-at-a-time "
        "study (LE2, LE3, LE4, LE7, JE1-JE6 at 0, +-0.02, +-0.05, +-0.07, +-0.1 %), Tables 2-3 "
        "(CSV, Markdown), Figures 2-7 (PNG), the comparison with the published values "
        "(comparison.md) and a JSON summary, written into renders/.")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default renders/, renders/recovered/ with --circle "
                        "recovered: generated output, replaced on "
                        "every run; in any other directory existing files are never replaced "
                        "without --force, checked before anything is computed)")
    p.add_argument("--force", action="store_true",
                   help="replace existing output files in --out")
    add_path_options(p)
    p.add_argument("--circle", choices=CIRCLES, default=None,
                   help="the paper's PUMA on a named circle: default (documented choice, "
                        "held hand) or recovered (fitted to the published Tables 2-3, hand "
                        "turning; output into renders/recovered/ unless --out). Without "
                        "trajectory options the default circle is used")
    plots = p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    deprecated_alias(p, "--no-figures", plots)
    p.add_argument("--no-video", action="store_true",
                   help="skip the video of the nominal and perturbed arm")
    add_progress(p)
    p.set_defaults(func=_paper, api_names={"q0": "--q0", "steps": "--steps",
                                           "circle": "--circle"})


_TRAJECTORY_DEFAULTS = {"joints": None, "q0": None, "radius": 125.0, "normal": None,
                        "toward": None, "duration": 4.0, "time_law": "quintic"}


def _named_circle(args: argparse.Namespace, model: Manipulator) -> str | None:
    """The named circle to run ("default" / "recovered"), or None for a custom trajectory;
    --circle with trajectory options or another model is an error naming them."""
    from zrp.paper.scenario import is_paper_model  # on use: keeps --help quick

    custom = [f"--{k.replace('_', '-')}" for k, v in _TRAJECTORY_DEFAULTS.items()
              if getattr(args, k) != v]
    if args.circle is None:
        return "default" if not custom and is_paper_model(model) else None
    if custom or not is_paper_model(model):
        what = ", ".join(custom) if custom else f"--model {args.model}"
        raise InputError(f"--circle: names a circle of the paper's Table 1 PUMA; it cannot be "
                         f"combined with {what}")
    return str(args.circle)


def _video_name(args: argparse.Namespace, model: Manipulator) -> str | None:
    """The video's file name (.mp4, or .gif without ffmpeg), or None when none is made."""
    from zrp.paper.scenario import is_paper_model  # on use: keeps --help quick
    from zrp.paper.scenes import paper_video_file_name  # on use: keeps --help quick

    if args.no_video or not is_paper_model(model):
        return None
    # sim loads MuJoCo and its GL backend (about 0.3 s measured): only when a video is made
    import sim

    return sim.video_path(paper_video_file_name()).name


def _video(args: argparse.Namespace, folder: OutputDir, name: str | None,
           model: Manipulator, circle: str) -> dict[str, Any]:
    """Render the nominal-vs-perturbed video of the paper's circle into the locked folder."""
    from zrp.paper.scenes import paper_video_scene  # on use: keeps --help quick

    if args.no_video:
        return {"status": "skipped (--no-video)"}
    if name is None:
        return {"status": "skipped (the video shows the paper's Table 1 PUMA only)"}
    # sim loads MuJoCo and its GL backend (about 0.3 s measured): only when a video is made
    import sim

    scene = paper_video_scene(steps=args.steps, circle=circle)
    try:
        with folder.path(name) as tmp:
            sim.render_video(scene.segments, tmp, title=scene.title, overwrite=True,
                             options=sim.VideoOptions(magnify=scene.magnify),
                             progress=draw_bar(args), progress_name=name)
    except (sim.GLUnavailableError, sim.GLBackendError) as exc:
        # no OpenGL backend on this machine: the tables and figures are still valid
        return {"status": f"skipped (no offscreen OpenGL: {exc})"}
    return {"status": "written", "path": str(folder.root / name)}


def _compute(args: argparse.Namespace, model: Manipulator, out: OutputDir
             ) -> tuple[PaperExample, list[Path], float]:
    """IK, study, comparison and claims, written into the (checked and locked) folder."""
    from zrp.paper.example import run_paper_example  # on use: keeps --help quick
    from zrp.paper.report import write_paper_outputs  # on use: keeps --help quick

    t0 = time.perf_counter()
    circle = _named_circle(args, model)
    path = None if circle else path_from_args(args, model)
    t_path = time.perf_counter() - t0
    ex = run_paper_example(model, path, steps=args.steps, circle=circle)
    if path is not None:
        ex.timings_s["inverse_kinematics"] = t_path
    ex.timings_s["total_compute"] = sum(v for k, v in ex.timings_s.items()
                                        if k != "total_compute")
    t0 = time.perf_counter()
    files = write_paper_outputs(ex, out, figures=not args.no_plots)
    return ex, files, time.perf_counter() - t0


def _output_folder(args: argparse.Namespace) -> tuple[Path, bool]:
    """The output folder (renders/, renders/recovered/ with --circle recovered, or --out) and
    whether its files may be replaced."""
    if args.out is None:
        args.out = DEFAULT_OUT + ("/recovered" if args.circle == "recovered" else "")
    out = Path(args.out)
    overwrite = args.force or (out in (Path(DEFAULT_OUT), Path(DEFAULT_OUT) / "recovered")
                               and claim_generated(out))
    return out, overwrite


def _comparison_lines(ex: PaperExample, counts: dict[str, int]) -> list[str]:
    """The summary of the comparison with the published Tables 2-3."""
    if not ex.cells:
        return ["no published values for this model: the paper's checks only", ""]
    le_ratio = [c.ratio for c in ex.cells if c.status == "match"]
    le3 = [c.ratio for c in ex.cells if c.column == "LE3" and c.table == 2]
    lines = [
        f"comparison with the published Tables 2-3 on the {ex.circle} circle (ratio = ours "
        "/ published):",
        f"  match to the printed digits: {counts.get('match', 0)} cells (ratios "
        f"{min(le_ratio):.4f}..{max(le_ratio):.4f})",
        f"  LE3 discrepancy: ratios {min(le3):.3f}..{max(le3):.3f} (published values imply "
        f"||b_3|| = 444.5 mm = 17.5 in vs 431.8 mm = 17 in in Table 1)",
        f"  likely typos (Table 2, 0.1 %): JE1 7.88E+0, JE2 1.33E-1 -> "
        f"{counts.get('typo', 0)} cells",
    ]
    if ex.circle == "recovered":
        lines.append(f"  reproduced within 5 % (not to the printed digits): "
                     f"{counts.get('reproduced', 0)} cells")
    else:
        lines.append(f"  trajectory-dependent JE cells: "
                     f"{counts.get('trajectory-dependent', 0)} (on the circle recovered "
                     "from the tables they are reproduced: `zrp paper --circle recovered`, "
                     "comparison.md)")
    lines.append("")
    return lines


def _claims_lines(ch: dict[str, Any], circle: str) -> list[str]:
    """The summary of the paper's claims checked on our numbers."""
    import textwrap

    from zrp.paper.claims import je_over_le_text  # on use: keeps --help quick

    lin = ch["linearity"]["ours_delta_p"]
    je_le = je_over_le_text(ch, circle)
    return [
        "claims:",
        f"  linearity: min R^2 over columns {min(v['r2'] for v in lin.values()):.6f}",
        *textwrap.wrap(je_le, 96, initial_indent="  ", subsequent_indent="    "),
        f"  link errors change the orientation by at most {ch['link_errors_max_angle_rad']:.3g}"
        " rad",
        "",
    ]


def _paper(args: argparse.Namespace) -> int:
    from zrp.model.files import load_model  # on use: keeps --help quick
    from zrp.paper.report import output_names  # on use: keeps --help quick

    out, overwrite = _output_folder(args)
    model = load_model(args.model)
    check_path_options(args, model)
    _named_circle(args, model)
    video_name = _video_name(args, model)
    names = [*output_names(figures=not args.no_plots), *([video_name] if video_name else []),
             INDEX_NAME]
    with OutputDir(out, overwrite=overwrite, names=names) as folder:
        ex, files, t_write = _compute(args, model, folder)
        video = _video(args, folder, video_name, model, ex.circle)
        index = write_index(folder)
    counts: dict[str, int] = {}
    for c in ex.cells:
        counts[c.status] = counts.get(c.status, 0) + 1
    ch = ex.checks
    payload = {
        "output_dir": str(out), "files": [str(f) for f in files], "video": video,
        "circle": ex.circle, "index": str(index),
        "sign_convention": ex.study.convention, "trajectory": ex.path.label,
        "compute_s": ex.timings_s, "write_s": t_write, "cell_status_counts": counts,
        "cells": [vars(c) for c in ex.cells], "checks": ch,
    }
    lines = [
        f"{model.name}: {ex.path.label} ({ex.study.t.size} samples)",
        f"convention: {ex.study.convention}",
        f"compute {ex.timings_s['total_compute'] * 1e3:.1f} ms (IK "
        f"{ex.timings_s['inverse_kinematics'] * 1e3:.1f} ms, study "
        f"{ex.timings_s['study'] * 1e3:.1f} ms); writing {t_write:.2f} s",
        "",
        *_comparison_lines(ex, counts),
        *_claims_lines(ch, ex.circle),
        f"video: {video['status']}" + (f" -> {video['path']}" if "path" in video else ""),
        f"wrote {len(files)} files into {out}/ (tables, figures, comparison.md, "
        "paper_example.json); index of every output: " + str(index),
    ]
    emit(args, payload, "\n".join(lines))
    return 0
