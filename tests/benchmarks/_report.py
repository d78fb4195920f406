"""The benchmark scripts' generated result files: ``renders/benchmarks/<name>.md`` (+ ``.json``).

Every ``bench_*.py`` collects its tables in a :class:`Report` and writes them here instead of
having them copied into a README by hand. Each file states when, where and how it was made:
the date, the machine (cores, CPU model, the CPU numba compiles for, load average), the
versions (Python, NumPy, SciPy, numba, MuJoCo, zrp with its git commit) and the exact command.

Output policy (the toolkit's, ``zrp.output``): the default folder ``renders/benchmarks/`` is
generated output and its files are replaced by the next run; a file named with ``--out``
elsewhere is replaced only with ``--force``. The check runs before the benchmark does
(:func:`output_path`), so a refused file costs no measuring.

Typical use in a script::

    ap = argparse.ArgumentParser(...)
    add_output_arguments(ap, "bench_x")
    args = ap.parse_args()
    out = output_path(args)                  # checked now, before any measuring
    report = Report("bench_x", "what it measures")
    report.table("Speed", ["figure", "value", "target"], rows)
    report.write(out, args)                  # bench_x.md and bench_x.json
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import shlex
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_DIR = ROOT / "renders" / "benchmarks"
_VERSIONED = ("numpy", "scipy", "numba", "mujoco", "pinocchio")


def default_path(name: str) -> Path:
    """``renders/benchmarks/<name>.md`` of this checkout."""
    return DEFAULT_DIR / f"{name}.md"


def add_output_arguments(ap: argparse.ArgumentParser, name: str) -> None:
    """``--out FILE.md`` (default ``renders/benchmarks/<name>.md``) and ``--force``."""
    ap.add_argument("--out", metavar="FILE.md", default=None,
                    help=f"Markdown file to write, with a .json beside it (default "
                         f"renders/benchmarks/{name}.md: generated output, replaced)")
    ap.add_argument("--force", action="store_true",
                    help="replace an existing --out file (the default file is always replaced)")
    ap.set_defaults(report_name=name)


def output_path(args: argparse.Namespace) -> Path:
    """The Markdown file to write, checked before the benchmark runs: an explicit ``--out``
    that exists (or its .json) is refused without ``--force`` (SystemExit, exit code 2)."""
    from zrp.output import claim_generated

    out = Path(args.out) if args.out else default_path(args.report_name)
    if out.suffix != ".md":
        print(f"error: --out: expected a .md file name, got {str(out)!r}", file=sys.stderr)
        raise SystemExit(2)
    # the default folder is generated output (marked as such), replaced without --force
    args.replace = bool(args.force) or (args.out is None and _refused(claim_generated,
                                                                      out.parent))
    check_outputs(args, [out, out.with_suffix(".json")])
    return out


def check_outputs(args: argparse.Namespace, paths: Sequence[Path]) -> None:
    """Refuse (SystemExit, exit code 2, naming ``--force``) files that exist when
    ``args.replace`` (set by :func:`output_path`) is false."""
    from zrp.output import check_writable

    _refused(check_writable, paths, overwrite=args.replace)


def _refused(fn: Any, *a: Any, **kw: Any) -> Any:
    from zrp.errors import OutputExistsError, ZRPError

    try:
        return fn(*a, **kw)
    except ZRPError as exc:
        msg = exc.message("--force") if isinstance(exc, OutputExistsError) else str(exc)
        print(f"error: --out: {msg}", file=sys.stderr)
        raise SystemExit(2) from None


def _git(*argv: str) -> str:
    try:
        res = subprocess.run(["git", *argv], cwd=ROOT, capture_output=True, text=True,
                             timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return ""
    return res.stdout.strip() if res.returncode == 0 else ""


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _numba_cpu() -> str:
    try:
        import llvmlite.binding as llvm

        return llvm.get_host_cpu_name()
    except Exception:  # optional detail: any failure leaves it out
        return ""


def _versions() -> dict[str, str]:
    from importlib import metadata

    out = {"python": platform.python_version()}
    for name in _VERSIONED:
        dist = "pin" if name == "pinocchio" else name
        try:
            out[name] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            continue
    import zrp

    commit = _git("rev-parse", "--short=12", "HEAD")
    dirty = " (modified)" if commit and _git("status", "--porcelain", "--untracked-files=no") \
        else ""
    out["zrp"] = f"{zrp.__version__}" + (f", commit {commit}{dirty}" if commit else "")
    return out


def command_line(argv: Sequence[str] | None = None) -> str:
    """The command as typed from the repository root (the script path made relative)."""
    argv = list(sys.argv if argv is None else argv)
    script = Path(argv[0]).resolve()
    try:
        argv[0] = script.relative_to(ROOT).as_posix()
    except ValueError:
        argv[0] = script.name
    return " ".join(["python3", *(shlex.quote(a) for a in argv)])


def machine() -> dict[str, Any]:
    """Cores, CPU model, the CPU numba compiles for, system and load average."""
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return {"cores": os.cpu_count(), "cpu": _cpu_model(), "numba_cpu": _numba_cpu(),
            "system": f"{platform.system()} {platform.release()}",
            "load_average_1min": round(load[0], 2)}


class Report:
    """Tables and notes of one benchmark run, written as Markdown and JSON."""

    def __init__(self, name: str, title: str) -> None:
        self.name, self.title = name, title
        self.started = _dt.datetime.now(_dt.timezone.utc)
        self.machine_start = machine()
        self.sections: list[dict[str, Any]] = []

    def table(self, heading: str, columns: Sequence[str], rows: Sequence[Sequence[Any]],
              note: str = "", readme: bool = False) -> None:
        """A table (cells printed with ``str``) under ``heading``, with an optional note;
        ``readme``: it follows the first table in the README's generated block too."""
        self.sections.append({"heading": heading, "columns": [str(c) for c in columns],
                              "rows": [[str(c) for c in r] for r in rows], "note": note,
                              **({"readme": True} if readme else {})})

    def note(self, heading: str, text: str) -> None:
        """A paragraph of text under ``heading``."""
        self.sections.append({"heading": heading, "columns": [], "rows": [], "note": text})

    def meta(self, argv: Sequence[str] | None = None) -> dict[str, Any]:
        end = machine()
        return {"benchmark": self.name, "title": self.title,
                "date": self.started.strftime("%Y-%m-%d %H:%M UTC"),
                "command": command_line(argv), "machine": self.machine_start,
                "load_average_at_end": end["load_average_1min"], "versions": _versions()}

    def markdown(self, meta: dict[str, Any]) -> str:
        m = meta["machine"]
        cpu = m["cpu"] + (f" (numba target `{m['numba_cpu']}`)" if m["numba_cpu"] else "")
        versions = ", ".join(f"{k} {v}" for k, v in meta["versions"].items())
        lines = [f"# {self.name}: {self.title}", "",
                 f"Generated by `{meta['command']}`; do not edit by hand (run it again).", "",
                 "| | |", "|---|---|", f"| date | {meta['date']} |",
                 f"| machine | {m['cores']} cores, {cpu}, {m['system']} |",
                 f"| load average | {m['load_average_1min']} at the start, "
                 f"{meta['load_average_at_end']} at the end |",
                 f"| versions | {versions} |", f"| command | `{meta['command']}` |"]
        for sec in self.sections:
            lines += ["", f"## {sec['heading']}", ""]
            if sec["columns"]:
                lines += [_row(sec["columns"]), _row(["---"] * len(sec["columns"])),
                          *(_row(r) for r in sec["rows"])]
                if sec["note"]:
                    lines.append("")
            if sec["note"]:
                lines.append(sec["note"])
        return "\n".join(lines) + "\n"

    def write(self, out: Path, args: argparse.Namespace,
              argv: Sequence[str] | None = None) -> Path:
        """Write ``out`` (Markdown) and the same content as JSON beside it; returns ``out``
        (``args`` as checked by :func:`output_path`)."""
        from zrp.output import write_json, write_text

        meta = self.meta(argv)
        replace = bool(getattr(args, "replace", False))
        write_text(out, self.markdown(meta), overwrite=replace)
        write_json(out.with_suffix(".json"), {**meta, "sections": self.sections},
                   overwrite=replace)
        print(f"wrote {_shown(out)} and {out.with_suffix('.json').name}")
        return out


def _row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


def _shown(path: Path) -> str:
    try:
        return path.resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return str(path)
