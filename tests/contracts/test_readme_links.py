"""Every relative link in the tracked Markdown files resolves, and the root README stays short.

* A link to a file or folder of the repository must exist; a ``#anchor`` must name a heading
  of the target file (GitHub's slugs: lower case, punctuation dropped, spaces -> hyphens,
  ``-1``, ``-2`` ... for repeated headings).
* A link into ``renders/`` (generated output, git-ignored) cannot exist in a clean checkout:
  it must instead match an entry of :data:`GENERATED`, which names the command or script that
  writes it, and the producer must exist and mention the file's name in its source.
* The root README is at most 150 lines and its first ``bash`` block holds exactly the two
  commands (install and run; install the test extra and run the tests: CI runs the second).
"""

from __future__ import annotations

import ast
import functools
import inspect
import re
import subprocess
from fnmatch import fnmatch
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
SOURCES = ("zrp", "sim", "mjcf", "tests/benchmarks")

#: Generated outputs that Markdown may link to: (pattern under renders/, producer). A producer
#: is ``zrp <command>`` (a registered subcommand) or a script path (``{stem}``: the link's
#: file name without its suffix).
GENERATED: tuple[tuple[str, str], ...] = (
    ("renders/benchmarks/bench_*.md", "tests/benchmarks/{stem}.py"),
    ("renders/benchmarks/bench_*.json", "tests/benchmarks/{stem}.py"),
    ("renders/benchmarks/bench_gap_benchmark/*", "tests/benchmarks/bench_gap_benchmark.py"),
    ("renders/gap_benchmark/*", "zrp gap-benchmark"),
    ("renders/motion_benchmark/*", "zrp motion-benchmark"),
    ("renders/plan_benchmark/*", "zrp plan-benchmark"),
    ("renders/lessons/*", "zrp lessons"),
    ("renders/recovered/*", "zrp paper"),
    ("renders/index.html", "zrp index"),
    ("renders/comparison.*", "zrp paper"),
    ("renders/table*", "zrp paper"),
    ("renders/fig*.png", "zrp paper"),
    ("renders/paper_example.json", "zrp paper"),
)

_FENCE = re.compile(r"^\s*(```|~~~)")
_INLINE_LINK = re.compile(
    r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\([ \t]*\n?[ \t]*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_REF_LINK = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$")
_CODE_SPAN = re.compile(r"(`+)(.+?)\1")
_HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")


def tracked_markdown() -> list[Path]:
    """The repository's tracked *.md files (every *.md outside renders/ without git)."""
    try:
        out = subprocess.run(["git", "ls-files", "*.md"], cwd=ROOT, capture_output=True,
                             text=True, check=True, timeout=30).stdout.split()
        return sorted(ROOT / f for f in out if (ROOT / f).is_file())
    except (OSError, subprocess.SubprocessError):
        skip = {"renders", ".git", ".venv", "build", "dist"}
        return sorted(p for p in ROOT.rglob("*.md")
                      if not skip & set(p.relative_to(ROOT).parts))


def prose(text: str) -> str:
    """The text with fenced code blocks and inline code spans blanked (line numbers kept)."""
    out, fenced = [], False
    for line in text.splitlines():
        if _FENCE.match(line):
            fenced = not fenced
            out.append("")
            continue
        out.append("" if fenced else _CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line))
    return "\n".join(out)


def links(path: Path) -> list[tuple[int, str]]:
    """(line number, target) of every inline, image and reference-style link (an inline link
    may break its line after the opening parenthesis, as CommonMark allows)."""
    text = prose(path.read_text(encoding="utf-8"))
    found = [(text.count("\n", 0, m.start()) + 1, m.group(1))
             for m in _INLINE_LINK.finditer(text)]
    found += [(no, m.group(1)) for no, line in enumerate(text.splitlines(), 1)
              if (m := _REF_LINK.match(line))]
    return sorted(found, key=lambda f: f[0])


def slug(heading: str) -> str:
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links: their text
    text = re.sub(r"<[^>]+>", "", text).replace("`", "")
    text = re.sub(r"[^\w\- ]", "", text.lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading anchor of a Markdown file (repeats numbered as GitHub does)."""
    seen: dict[str, int] = {}
    out = set()
    text = path.read_text(encoding="utf-8")
    fenced = False
    for line in text.splitlines():
        if _FENCE.match(line):
            fenced = not fenced
            continue
        m = None if fenced else _HEADING.match(line)
        if m:
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f"{base}-{n}")
    return out


def _is_external(target: str) -> bool:
    return bool(re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target)) or target.startswith("//")


def _producer(rel: str) -> str | None:
    for pattern, producer in GENERATED:
        if fnmatch(rel, pattern):
            return producer.format(stem=Path(rel).stem)
    return None


@functools.cache
def commands() -> dict[str, Path]:
    """``zrp`` subcommand -> the source file of the function it runs."""
    from zrp.cli.app import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return {name: Path(inspect.getsourcefile(p.get_default("func")))
            for name, p in sub.choices.items()}


def _source_mentions(files: list[Path], name: str) -> bool:
    return any(name in f.read_text(encoding="utf-8") for f in files)


def check_generated(rel: str) -> str | None:
    """Why the renders/ link ``rel`` is not accounted for (None when it is)."""
    producer = _producer(rel)
    if producer is None:
        return (f"{rel} is generated output (git-ignored): add the command or script that "
                f"writes it to GENERATED in tests/contracts/test_readme_links.py")
    name = Path(rel).name
    if producer.startswith("zrp "):
        if producer[4:] not in commands():
            return f"{rel}: its producer `{producer}` is not a zrp command"
        files = [p for d in SOURCES for p in (ROOT / d).rglob("*.py")]
        if not _source_mentions(files, name):
            return f"{rel}: no source file of {', '.join(SOURCES)} names {name!r}"
        return None
    script = ROOT / producer
    if not script.is_file():
        return f"{rel}: its producer {producer} does not exist"
    tree = ast.parse(script.read_text(encoding="utf-8"))
    declared = {a.args[1].value for a in ast.walk(tree) if isinstance(a, ast.Call)
                and getattr(a.func, "id", "") == "add_output_arguments" and len(a.args) == 2
                and isinstance(a.args[1], ast.Constant)}
    if script.stem not in declared:
        return f"{rel}: {producer} does not write renders/benchmarks/{script.stem}.md"
    return None


def check_link(md: Path, target: str, root: Path = ROOT) -> str | None:
    """Why ``target`` (a link in ``md``, a file under ``root``) does not resolve (None when
    it does)."""
    if _is_external(target):
        return None
    path_part, _, anchor = target.partition("#")
    dest = (md.parent / unquote(path_part)).resolve() if path_part else md
    try:
        rel = dest.relative_to(root.resolve()).as_posix()
    except ValueError:
        return f"{target}: points outside the repository"
    if rel == "renders" or rel.startswith("renders/"):
        return check_generated(rel)
    if not dest.exists():
        return f"{target}: {rel} does not exist"
    if anchor and dest.suffix == ".md" and anchor not in anchors(dest):
        return f"{target}: {rel} has no heading with the anchor #{anchor}"
    return None


MARKDOWN = tracked_markdown()


def test_markdown_files_found():
    assert README in MARKDOWN and len(MARKDOWN) >= 5, MARKDOWN


@pytest.mark.parametrize("md", MARKDOWN, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(md):
    problems = [f"{md.relative_to(ROOT)}:{no}: {why}" for no, target in links(md)
                if (why := check_link(md, target))]
    assert not problems, ("broken links (fix the link, or the heading/file it names; links "
                          "into renders/ need a producer in GENERATED):\n  "
                          + "\n  ".join(problems))


def test_generated_patterns_have_producers():
    """Each GENERATED producer exists (a zrp command or a script)."""
    missing = []
    for _pattern, producer in GENERATED:
        if producer.startswith("zrp "):
            if producer[4:] not in commands():
                missing.append(producer)
        elif "{stem}" not in producer and not (ROOT / producer).is_file():
            missing.append(producer)
    assert not missing, missing


def test_root_readme_is_short():
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= 150, f"README.md has {n} lines; the limit is 150 (move detail to a package " \
        "README)"


def test_root_readme_first_bash_block_is_the_two_commands():
    """CI (.ci/run) runs the second line verbatim as the test command."""
    text = README.read_text(encoding="utf-8")
    m = re.search(r"^```bash\n(.*?)^```$", text, flags=re.S | re.M)
    assert m, "README.md has no ```bash block"
    lines = m.group(1).splitlines()
    assert len(lines) == 2 and all(line.strip() for line in lines), lines
    assert "pip install" in lines[0] and "pytest" in lines[1], lines


# The checker itself, on small cases (so that a broken checker cannot pass everything).

def test_slugs_follow_github():
    assert slug("The gap in motion (`zrp diagnose-motion`, `zrp.gap.motion`)") == \
        "the-gap-in-motion-zrp-diagnose-motion-zrpgapmotion"
    assert slug("Measuring (`sim/measurement.py`, `zrp measure`)") == \
        "measuring-simmeasurementpy-zrp-measure"
    assert slug("Model files: TOML & DH") == "model-files-toml--dh"
    assert slug("[Link](x.md) text") == "link-text"


def test_checker_finds_broken_links_and_anchors(tmp_path):
    md = tmp_path / "a.md"
    md.write_text("# Title\n\n## Two words\n\n## Two words\n\n[ok](#two-words-1) [bad](#nope)\n"
                  "[file](b.md#title) [gone](c.md) `[code](c.md)`\n\n```\n[fenced](c.md)\n```\n"
                  "[web](https://example.org/x) [ref]: d.md\n[r]: e.md\n[split](\nc.md)\n",
                  encoding="utf-8")
    (tmp_path / "b.md").write_text("# Title\n", encoding="utf-8")
    found = [t for _no, t in links(md)]
    assert found == ["#two-words-1", "#nope", "b.md#title", "c.md", "https://example.org/x",
                     "e.md", "c.md"]
    assert [no for no, _t in links(md)][-2:] == [14, 15]
    bad = {t for t in found if check_link(md, t, root=tmp_path)}
    assert bad == {"#nope", "c.md", "e.md"}
    assert "outside" in check_link(md, "../../x.md", root=tmp_path)


def test_renders_links_need_a_producer():
    assert check_generated("renders/benchmarks/bench_kinematics.md") is None
    assert check_generated("renders/gap_benchmark/summary.md") is None
    assert {"ik", "paper", "gap-benchmark", "index"} <= set(commands())
    assert "GENERATED" in check_generated("renders/unknown.txt")
    assert "does not exist" in check_generated("renders/benchmarks/bench_nothing.md")
