"""``index.html``: one page linking every output in a folder (``renders/``) with one sentence
each on what it shows; images shown inline, videos playable.

The page opens with a "start here" path for a student (:func:`start_here_html`): the executed
teaching notebooks in order (``notebooks/*.html``, written by ``zrp notebooks``), then the
paper's figures, the videos and the reports; every file follows, one sentence each.

A sentence comes from, in order: a ``descriptions.json`` in the file's folder (file name ->
sentence; the lessons write one), the :data:`CATALOGUE` of known outputs (shell patterns on
the path relative to the root), else a plain statement that no description is registered.
Links are relative (only: :func:`zrp.escape.file_href`), so the page works wherever the folder
is copied, and every name is shown as text.
"""

from __future__ import annotations

import html
import json
import os
from fnmatch import fnmatch
from pathlib import Path

from zrp.errors import InputError
from zrp.escape import file_href, html_text
from zrp.output import LOCK_NAME, OutputDir, write_text

__all__ = ["CATALOGUE", "INDEX_NAME", "START_HERE", "index_entries", "index_html",
           "start_here_html", "write_described_index", "write_index"]

INDEX_NAME = "index.html"
DESCRIPTIONS = "descriptions.json"
#: Known outputs: (pattern on the relative path, one sentence on what it shows). The first
#: match wins, and ``*`` also matches ``/``: a folder's pattern comes before its files'.
CATALOGUE: tuple[tuple[str, str], ...] = (
    ("*_joints.csv", "The joint trajectory of `zrp ik` with per-step diagnostics "
                     "(manipulability, damping, drift, correction)."),
    ("table2_max_position.*", "Table 2 as the paper prints it: the maximum positional deviation "
                              "(mm) of each parameter at each perturbation level."),
    ("table2_full.csv", "Table 2 with the negative levels too."),
    ("table3_max_rotation.*", "Table 3 as the paper prints it: the maximum rotational deviation "
                              "of eq (15) for each joint-axis error."),
    ("table3_full.csv", "Table 3 with the negative levels too."),
    ("table3_angle_rad.*", "Table 3 as plain error angles (rad) instead of eq (15)."),
    ("fig2_je_max_position*.png", "Figure 2: maximum positional deviation against the "
                                  "joint-axis perturbation, ours beside the published squares."),
    ("fig3_je_max_rotation*.png", "Figure 3: maximum rotational deviation (eq 15, with the plain "
                                  "angle on the right axis) against the joint-axis perturbation."),
    ("fig4_le_max_position*.png", "Figure 4: maximum positional deviation against the link "
                                  "perturbation: a straight line of slope ||b_k||."),
    ("fig5_je_position_time_recovered.png", "Figure 5 on the circle recovered from the "
                                            "published Tables 2-3."),
    ("fig6_je_rotation_time_recovered.png", "Figure 6 on the circle recovered from the "
                                            "published Tables 2-3."),
    ("fig7_le_position_time_recovered.png", "Figure 7 on the circle recovered from the "
                                            "published Tables 2-3 (identical: link errors do "
                                            "not depend on the circle)."),
    ("fig5_je_position_time.png", "Figure 5: positional deviation along the circle for each "
                                  "joint-axis error at 0.1 %."),
    ("fig6_je_rotation_time.png", "Figure 6: rotational deviation along the circle for each "
                                  "joint-axis error at 0.1 %."),
    ("fig7_le_position_time.png", "Figure 7: positional deviation along the circle for each link "
                                  "error at 0.1 %: constant in time."),
    ("comparison.md", "Every published cell of Tables 2-3 beside ours, with the ratio and why "
                      "they differ, and the recovered circle."),
    ("comparison.csv", "The same comparison as a CSV table."),
    ("paper_example.json", "The paper example's numbers (tables, checks, timings) as JSON."),
    ("puma_circle_*pct.*", "Video: the perturbed PUMA drawing the circle beside its nominal "
                           "ghost, deviations magnified by a stated factor."),
    ("puma_sweep_*.*", "Video: the same circle once per perturbation level, at one "
                       "magnification, earlier traces kept: the deviation grows with xi."),
    ("*index.html", "The index page of that folder's outputs."),
    ("gap_benchmark/*", "Output of the blind benchmark of the gap diagnosis (`zrp "
                        "gap-benchmark`)."),
    ("motion_benchmark/*", "Output of the blind benchmark of the motion diagnosis (`zrp "
                           "motion-benchmark`)."),
    ("plan_benchmark/*", "Output of the planned-against-random measurement study (`zrp "
                         "plan-benchmark`)."),
    ("benchmarks/bench_*/*", "A benchmark script's detailed tables (tests/benchmarks/, the "
                             "script of the folder's name)."),
    ("benchmarks/bench_*.md", "Measured results of a benchmark script (tests/benchmarks/, "
                              "the file of the same name): the date, machine, versions and "
                              "exact command, then its tables."),
    ("benchmarks/bench_*.json", "The same measured results as JSON."),
)
_FALLBACK = "Generated output of a zrp command (no description registered for this file)."


def _descriptions(folder: Path) -> dict[str, str]:
    f = folder / DESCRIPTIONS
    if not f.is_file():
        return {}
    try:
        data = json.loads(f.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"{f}: cannot read the file descriptions ({exc})") from exc
    if not isinstance(data, dict):
        raise InputError(f"{f}: expected a JSON object (file name -> sentence)")
    return {str(k): str(v) for k, v in data.items()}


def _sentence(rel: str) -> str:
    """The catalogue's sentence for ``rel``: by its path, else by its name (noting the
    recovered circle for files under ``recovered/``)."""
    name = rel.rsplit("/", 1)[-1]
    for key in (rel, name):
        found = next((s for pat, s in CATALOGUE if fnmatch(key, pat)), None)
        if found is not None:
            if key == name != rel and rel.startswith("recovered/"):
                found += " On the circle recovered from the published Tables 2-3."
            return found
    return _FALLBACK


def index_entries(root: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """(relative path, sentence) for every output file under ``root``, sorted by path
    (the index itself, lock files, hidden files and ``descriptions.json`` excluded)."""
    root = Path(root)
    out = []
    for f in sorted(root.rglob("*")):
        rel = f.relative_to(root).as_posix()
        if (not f.is_file() or rel == INDEX_NAME or f.name in (LOCK_NAME, DESCRIPTIONS)
                or any(part.startswith(".") for part in f.relative_to(root).parts)):
            continue
        sentence = _descriptions(f.parent).get(f.name) or _sentence(rel)
        out.append((rel, sentence))
    return out


def _preview(rel: str) -> str:
    href = file_href(rel)
    ext = Path(rel).suffix.lower()
    if ext in (".png", ".gif", ".jpg"):
        return (f'<br><img src="{href}" alt="{html_text(rel)}" loading="lazy" '
                'style="max-width:640px">')
    if ext == ".mp4":
        return f'<br><video src="{href}" controls muted style="max-width:640px"></video>'
    return ""


#: The student's path: (section title, what it is for, patterns of the files it lists, in
#: order; the first pattern a file matches places it). Sections with no file are left out,
#: except the notebooks, which say how to make them.
START_HERE: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("Notebooks, in order", "Run them top to bottom in Jupyter (sources: "
     "sim/lessons/notebooks/), or read them executed here.", ("notebooks/[0-9]*.html",)),
    ("The paper's figures", "Figures 2-7 of the paper's example, ours beside the published "
     "values; comparison.md says cell by cell why they differ.",
     ("fig[2-7]_*[!d].png", "fig[2-7]_*_recovered.png", "comparison.md")),
    ("Videos", "The arm drawing the circle, deviations magnified by a stated factor.",
     ("*.mp4", "*.gif")),
    ("Reports", "Summaries of the benchmarks and studies.",
     ("*summary.md", "benchmarks/bench_*.md", "lessons/index.html")),
)
_NO_NOTEBOOKS = ("not executed yet: <code>zrp notebooks</code> (with the notebooks extra, "
                 "<code>pip install 'zrp-accuracy[notebooks]'</code>) writes them here; the "
                 "sources are in <code>sim/lessons/notebooks/</code>.")


def start_here_html(entries: list[tuple[str, str]]) -> list[str]:
    """The "start here" section of the page for :func:`index_entries` ``entries``."""
    lines = ['<section id="start-here">', "<h2>Start here</h2>", "<ol>"]
    for i, (title, purpose, patterns) in enumerate(START_HERE):
        files = [(rel, sentence) for pat in patterns for rel, sentence in entries
                 if fnmatch(rel, pat)]
        files = list(dict.fromkeys(files))
        if not files and i > 0:
            continue
        lines.append(f"<li><strong>{html.escape(title)}</strong>: {html.escape(purpose)}")
        if files:
            lines += ["<ol>", *(f'<li><a href="{file_href(rel)}">'
                                f"{html_text(rel)}</a>: {html_text(sentence)}</li>"
                                for rel, sentence in files), "</ol>"]
        else:
            lines.append(f"<br>{_NO_NOTEBOOKS}")
        lines.append("</li>")
    return [*lines, "</ol>", "</section>"]


def index_html(root: str | os.PathLike[str], title: str = "zrp outputs") -> str:
    """The page (HTML5): one list item per :func:`index_entries` entry."""
    entries = index_entries(root)
    # relative links only, each component percent-encoded (zrp.escape): a file named
    # "javascript:alert(1)" is a link to that file, never a script
    items = [f'<li><a href="{file_href(rel)}">{html_text(rel)}</a>: '
             f"{html_text(sentence)}{_preview(rel)}</li>"
             for rel, sentence in entries]
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f"<title>{html.escape(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
        "li{margin:0 0 1.2em}</style>", "</head>", "<body>", f"<h1>{html.escape(title)}</h1>",
        *start_here_html(entries), '<section id="all-files">', "<h2>All files</h2>",
        f"<p>{len(items)} files, each with one sentence on what it shows.</p>",
        "<ul>", *items, "</ul>", "</section>", "</body>", "</html>", ""])


def write_described_index(folder: OutputDir, sentences: dict[str, str]) -> Path:
    """Write ``sentences`` (file name -> what it shows) to the entered ``folder``'s
    descriptions, keeping the earlier sentences of files still there that this run did not
    make (lessons or notebooks not run now), then its ``index.html``."""
    from zrp.jsonio import dumps  # on use: keeps the command line's help quick

    old_path = folder.root / DESCRIPTIONS
    if old_path.is_file():
        old = json.loads(old_path.read_text(encoding="utf-8"))
        sentences = {**{k: v for k, v in old.items() if (folder.root / k).is_file()},
                     **sentences}
    folder.write_text(DESCRIPTIONS, dumps(sentences))
    return write_index(folder)


def write_index(out: str | os.PathLike[str] | OutputDir, *, overwrite: bool = False) -> Path:
    """Write ``index.html`` into ``out`` (an entered :class:`OutputDir`, or a folder:
    an existing index is replaced only with ``overwrite=True``)."""
    if isinstance(out, OutputDir):
        return out.write_text(INDEX_NAME, index_html(out.root))
    root = Path(out)
    return write_text(root / INDEX_NAME, index_html(root), overwrite=overwrite)
