"""``zrp diagnose --data 'fleet/*.csv'``: one diagnosis per file, on a cluster or here, then the
fleet summary (fleet.md, fleet.csv, fleet.json, fleet.png)."""

from __future__ import annotations

import argparse
import glob
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from zrp.cli.app import emit
from zrp.cli.cluster import add_cluster_options, check_cluster_options, executor_from_args
from zrp.cli.fleet.summary import fleet_csv, fleet_figure, fleet_markdown, fleet_summary
from zrp.cli.options import LENGTH, draw_bar
from zrp.errors import InputError
from zrp.output import OutputDir, check_no_links, check_writable, safe_name
from zrp.tasks import TaskFailure, map_tasks

if TYPE_CHECKING:
    from zrp.cli.fleet.tasks import RobotTask

__all__ = ["FLEET_FILES", "add_fleet_options", "is_fleet", "refuse_fleet_options", "run_fleet"]

FLEET_FILES = ("fleet.md", "fleet.csv", "fleet.json", "fleet.png")
#: Written last by the per-robot report writer: its presence marks a finished robot.
DONE_MARKER = "report.md"


def is_fleet(data: str) -> bool:
    """``--data`` names a fleet: a glob pattern that is not itself an existing file."""
    return glob.has_magic(data) and not Path(data).exists()


def refuse_fleet_options(args: argparse.Namespace) -> None:
    """A single file: the fleet's options would be silently ignored, so refuse them."""
    for opt, given in (("--workers", args.workers is not None),
                       ("--scheduler", args.scheduler is not None), ("--resume", args.resume)):
        if given:
            raise InputError(f"{opt}: only for a fleet (--data with a quoted glob such as "
                             f"'fleet/*.csv'); {args.data!r} is one file")


def add_fleet_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("fleet (--data with a glob, e.g. 'fleet/*.csv')")
    g.add_argument("--tolerance", type=LENGTH, default=0.5, metavar="T",
                   help="a robot is out of tolerance when its largest withheld error after "
                        "registration exceeds T (length unit; default 0.5)")
    g.add_argument("--resume", action="store_true",
                   help="keep the robots an interrupted fleet run finished (OUT/robots/NAME/) "
                        "and diagnose only the others")
    add_cluster_options(p)


def _tasks(args: argparse.Namespace, files: list[Path], out: Path) -> list[RobotTask]:
    from zrp.cli.fleet.tasks import RobotTask  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick

    model = load_model(args.model)
    # a robot's folder is OUT/robots/NAME: NAME from the file's stem through the one
    # sanitiser, and neither robots/ nor NAME/ may be a link (even with --resume)
    names = [safe_name(f.stem, default="robot") for f in files]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"--data: robot names (file stems, as folder names) must be unique; "
                         f"repeated: {dup}")
    base = Path(os.path.abspath(out))  # not resolved: a link on the way is refused below
    mjcf = None if args.mjcf is None else Path(args.mjcf)
    if mjcf is not None and not mjcf.is_file():
        raise InputError(f"--mjcf: {mjcf} is not a file")
    opts = {"effects": args.effects, "seed": args.seed, "withheld_fraction": args.withheld,
            "folds": args.folds, "alpha": args.alpha, "max_steps": args.max_steps,
            "noise_sigma": args.noise, "progress": False,
            "use_orientation": not args.no_orientation,
            "orientation_sigma": args.orientation_sigma}
    read = {"deg": args.deg, "frame": args.frame}
    return [RobotTask(n, f.resolve(), check_no_links(base, base / "robots" / n), model, mjcf,
                      read, opts, not args.no_plots) for n, f in zip(names, files, strict=True)]


def _previous(tasks: list[RobotTask]) -> dict[str, dict[str, Any]]:
    """Rows of the robots an interrupted run finished."""
    from zrp.cli.fleet.tasks import robot_row  # on use: keeps --help quick
    from zrp.jsonio import MAX_DIAGNOSIS_BYTES, read_json  # on use: keeps --help quick

    done = {}
    for t in tasks:
        path = t.out / "diagnosis.json"
        if (t.out / DONE_MARKER).exists() and path.exists():
            try:
                done[t.name] = _checked_row(robot_row(t.name, str(t.data), read_json(
                    path, max_bytes=MAX_DIAGNOSIS_BYTES, what="diagnosis.json")))
            except (ValueError, KeyError, TypeError, AttributeError, IndexError,
                    RecursionError) as exc:  # JSONDecodeError, UnicodeDecodeError are ValueErrors
                raise InputError(f"--resume: {path}: not a diagnosis this toolkit wrote "
                                 f"(damaged: {type(exc).__name__}: {exc}); delete {t.out} to "
                                 "diagnose that robot again, or run with --force") from None
    return done


_ROW_NUMBERS = ("points", "error_rms", "error_p95", "error_max", "corrected_rms",
                "corrected_max", "shrink")


def _checked_row(row: dict[str, Any]) -> dict[str, Any]:
    """``row`` if its numbers are numbers (or null: a NaN written) and its lists lists
    (TypeError naming the field)."""
    for key in _ROW_NUMBERS:
        v = row[key]
        if v is not None and (not isinstance(v, (int, float)) or isinstance(v, bool)):
            raise TypeError(f"{key}: expected a number, got {v!r:.40}")
    for key in ("top_joints", "effects"):
        if not isinstance(row[key], list):
            raise TypeError(f"{key}: expected a list, got {row[key]!r:.40}")
    return row


def _diagnose_all(args: argparse.Namespace, todo: list[RobotTask]
                  ) -> tuple[list[dict[str, Any]], list[TaskFailure]]:
    from tqdm.auto import tqdm  # ~0.1 s (asyncio): only when a fleet runs

    from zrp.cli.fleet.tasks import diagnose_robot  # on use: keeps --help quick

    rows: list[dict[str, Any]] = []
    failures: list[TaskFailure] = []
    with executor_from_args(args) as ex, \
            tqdm(total=len(todo), desc="fleet", unit="robot", disable=not draw_bar(args)) as bar:
        for _, res in map_tasks(diagnose_robot, todo, ex, capture=True, describe=str):
            if isinstance(res, TaskFailure):
                failures.append(res)
            else:
                rows.append(res)
            bar.update(1)
            bar.set_postfix(failed=len(failures))
    return rows, failures


def _fleet_files(args: argparse.Namespace) -> list[Path]:
    """The robots' data files, after checking the cluster options and the tolerance."""
    check_cluster_options(args)
    if not args.tolerance > 0:
        raise InputError(f"--tolerance: expected a positive length, got {args.tolerance}")
    files = sorted(Path(f) for f in glob.glob(args.data) if Path(f).is_file())
    if not files:
        raise InputError(f"--data: no file matches {args.data!r}")
    return files


def _wanted(args: argparse.Namespace, names: tuple[str, ...]) -> list[str]:
    """``names`` less the plots under ``--no-plots``."""
    return [n for n in names if not (args.no_plots and n.endswith(".png"))]


def _write_fleet(folder: OutputDir, args: argparse.Namespace, doc: dict[str, Any]) -> None:
    folder.write_json("fleet.json", doc)
    folder.write_text("fleet.csv", fleet_csv(doc))
    if not args.no_plots and doc["rows"]:
        folder.savefig("fleet.png", fleet_figure(doc), dpi=110)
    folder.write_text("fleet.md", fleet_markdown(doc))


def run_fleet(args: argparse.Namespace) -> int:
    """The fleet run; exit code 1 when some robot could not be diagnosed (the rest was)."""
    from zrp.gap.report import OUTPUT_FILES  # on use: keeps --help quick

    files = _fleet_files(args)
    out = Path(args.out)
    tasks = _tasks(args, files, out)
    done = _previous(tasks) if args.resume else {}
    todo = [t for t in tasks if t.name not in done]
    overwrite = args.force or args.resume
    names = _wanted(args, FLEET_FILES)
    per_robot = _wanted(args, OUTPUT_FILES)
    # every file this run writes is checked before the first diagnosis
    check_writable([t.out / n for t in todo for n in per_robot], overwrite)
    with OutputDir(out, overwrite=overwrite, names=names) as folder:
        rows, failures = _diagnose_all(args, todo)
        unit = tasks[0].model.length_unit
        doc = fleet_summary(rows + list(done.values()), failures, args.tolerance, unit,
                            resumed=len(done))
        _write_fleet(folder, args, doc)
        files_written = list(folder.written)
    text = fleet_markdown(doc) + "\n".join(f"wrote {f}" for f in files_written)
    emit(args, doc, text)
    return 1 if failures else 0
