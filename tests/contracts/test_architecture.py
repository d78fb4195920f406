"""The layer contract, module size and the import-order independence of the public API.

Layers, lowest first: the core ``zrp`` (everything but ``zrp.cli``) -> ``mjcf`` -> ``sim`` ->
the command line ``zrp.cli``. A module never imports a layer above its own; the core uses only
the standard library, NumPy, SciPy, numba, tqdm and scikit-learn (Matplotlib only in report and plot
modules); no engine module imports a report module. The same contract runs in CI through
import-linter (``[tool.importlinter]`` in pyproject.toml); this test also covers what
import-linter cannot express (third-party allow-lists, report modules, function-local imports).

Two more gates: no import circle between modules (:func:`import_cycles`), and no function above
radon's cyclomatic complexity 15 (:func:`too_complex`; radon counts each ``and``/``or``, which
ruff's C901 does not).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("zrp", "mjcf", "sim")
LAYER = {"core": 0, "mjcf": 1, "sim": 2, "cli": 3}
# threadpoolctl: BLAS thread limits for the diagnosis (zrp/blas.py); sklearn: the Gaussian
# process and kernels of the test of what remains (zrp/gap/analysis/kernel.py, imported lazily);
# rosbags: ROS 1/2 bags read without ROS (zrp/gap/data/rosbag.py, imported lazily; issue 44)
CORE_THIRD_PARTY = {"numpy", "scipy", "numba", "tqdm", "tomli", "threadpoolctl", "sklearn",
                    "rosbags"}
REPORT_ONLY = {"matplotlib", "PIL"}
MAX_LINES = 400
MAX_COMPLEXITY = 15

# Functions of sim/** and zrp/gap/** still above MAX_COMPLEXITY while their split is under way
# on other branches (issue 21). The list may only shrink: each entry must still exist and still
# be above the limit (test_complexity_allowlist_only_shrinks); no other folder may be listed.
COMPLEXITY_ALLOWLIST: frozenset[str] = frozenset()
ALLOWLIST_FOLDERS = ("sim/", "zrp/gap/")

# Import circles being broken on other branches (issue 21), each as the set of modules it
# joins: a circle found must lie inside one of them, and each must still hold a circle.
CYCLE_ALLOWLIST: tuple[frozenset[str], ...] = ()


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def layer_of(module: str) -> str | None:
    top = module.split(".")[0]
    if top == "zrp":
        cli = module in ("zrp.cli", "zrp.__main__") or module.startswith("zrp.cli.")
        return "cli" if cli else "core"
    return top if top in ("mjcf", "sim") else None


def is_report(module: str) -> bool:
    """Report and plot modules: the only core modules that may use Matplotlib."""
    parts = module.split(".")
    return "report" in parts or parts[-1] in ("plots", "figures", "report")


def from_base(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The absolute module of ``from X import ...`` in ``module`` (relative X resolved)."""
    base = node.module or ""
    if node.level:
        pkg = module.split(".") if is_package else module.split(".")[:-1]
        pkg = pkg[: len(pkg) - (node.level - 1)]
        base = ".".join([*pkg, base] if base else pkg)
    return base


def report_owner(module: str) -> str:
    """The package whose report a report module is: zrp.gap for zrp.gap.report.plots (so that
    zrp.gap.analysis.where may not import it), zrp.manufacturing for zrp.manufacturing.plots."""
    parts = module.split(".")
    return ".".join(parts[:parts.index("report")] if "report" in parts[:-1] else parts[:-1])


def imports_of(source: str, module: str, is_package: bool) -> list[tuple[str, int, bool]]:
    """(imported module, line, function-local?) for every import statement."""
    tree = ast.parse(source)
    out: list[tuple[str, int, bool]] = []
    local_lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for sub in ast.walk(node):
                if isinstance(sub, (ast.Import, ast.ImportFrom)):
                    local_lines.add(sub.lineno)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno, node.lineno in local_lines) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = from_base(node, module, is_package)
            out.append((base, node.lineno, node.lineno in local_lines))
            # `from zrp import cli` imports the sub-package zrp.cli
            out += [(f"{base}.{a.name}", node.lineno, node.lineno in local_lines)
                    for a in node.names]
    return out


def violations(module: str, source: str, is_package: bool = False) -> list[str]:
    """Every import of ``module`` that breaks the contract, as readable lines."""
    mine = layer_of(module)
    bad: list[str] = []
    stdlib = sys.stdlib_module_names
    for target, line, _local in imports_of(source, module, is_package):
        top = target.split(".")[0]
        theirs = layer_of(target)
        where = f"{module} line {line} imports {target}"
        if theirs is not None and mine is not None and LAYER[theirs] > LAYER[mine]:
            bad.append(f"{where}: layer {theirs} is above {mine}")
        if mine == "core":
            if top == "mujoco":
                bad.append(f"{where}: the core never imports MuJoCo")
            elif top in REPORT_ONLY and not is_report(module):
                bad.append(f"{where}: plotting belongs in a report/plots module")
            elif (theirs is None and top not in stdlib and top not in CORE_THIRD_PARTY
                  and top not in REPORT_ONLY and top != "__future__"):
                bad.append(f"{where}: the core uses only NumPy/SciPy/numba/tqdm")
        if (theirs is not None and is_report(target) and not is_report(module)
                and not is_package and module.startswith(report_owner(target) + ".")):
            bad.append(f"{where}: an engine module never imports its report")
    return bad


def project_modules() -> list[tuple[str, Path]]:
    return sorted((module_name(p), p) for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def test_the_checker_catches_violations():
    """The contract check can fail: each kind of violation is caught in a made-up module."""
    assert violations("zrp.kinematics.forward", "import mujoco\n")
    assert violations("zrp.kinematics.forward", "def f():\n    import sim.view.playback\n")
    assert violations("zrp.gap.pipeline", "from mjcf import build\n")
    assert violations("zrp.model.files", "from zrp.cli.app import emit\n")
    assert violations("mjcf.builder", "import sim\n")
    assert violations("sim.view.video", "from zrp.cli import main\n")
    assert violations("zrp.gap.analysis.where", "import matplotlib.pyplot as plt\n")
    assert violations("zrp.gap.analysis.where", "import pandas\n")
    assert violations("zrp.gap.pipeline", "from zrp.gap.report.write import write_outputs\n")
    assert violations("zrp.gap.analysis.where", "from ..report import plots\n")
    # and lets the allowed ones through
    assert not violations("zrp.gap.report.plots", "import matplotlib\n")
    assert not violations("sim.view.video", "import mjcf\nimport mujoco\nimport zrp\n")
    assert not violations("zrp.cli.commands.render", "import sim\nimport mjcf\n")
    assert not violations("zrp.gap.fit.leastsq", "import numpy\nfrom scipy import special\n")


def test_layer_contract_holds_for_every_module():
    bad = []
    for name, path in project_modules():
        bad += violations(name, path.read_text(encoding="utf-8"), path.name == "__init__.py")
    assert not bad, "\n".join(bad)


def test_importing_the_core_loads_no_upper_layer():
    """In a fresh interpreter, `import zrp` (all of the core) loads neither MuJoCo, mjcf, sim
    nor the command line."""
    code = ("import sys, zrp, zrp.gap, zrp.manufacturing, zrp.paper, zrp.kinematics; "
            "bad = [m for m in ('mujoco', 'mjcf', 'sim', 'zrp.cli', 'matplotlib') "
            "if m in sys.modules]; print(bad); sys.exit(1 if bad else 0)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert res.returncode == 0, res.stdout + res.stderr


def test_function_local_project_imports_give_their_reason():
    """A function-local import of a project module needs a comment saying why (a measured
    import cost, MuJoCo's GL backend choice...) on its line or the line above."""
    bad = []
    for name, path in project_modules():
        lines = path.read_text(encoding="utf-8").splitlines()
        for target, line, local in imports_of("\n".join(lines), name, path.name == "__init__.py"):
            if local and layer_of(target) is not None:
                ctx = lines[line - 1] + (lines[line - 2] if line >= 2 else "")
                if "#" not in ctx:
                    bad.append(f"{name} line {line}: function-local import without a reason")
    assert not bad, "\n".join(sorted(set(bad)))


def _is_kernel(path: Path) -> bool:
    return path.name.startswith("_") and path.name.endswith("kernels.py")


def test_modules_stay_small():
    long = [f"{name}: {n} lines" for name, path in project_modules()
            if not _is_kernel(path)
            and (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES * 1.1]
    assert not long, "modules over ~400 lines:\n" + "\n".join(long)


def test_lint_imports_contract():
    """import-linter's run of the contracts in pyproject.toml (skipped if not installed)."""
    pytest.importorskip("importlinter")
    res = subprocess.run([sys.executable, "-m", "importlinter.cli", "--no-cache"],
                         capture_output=True, text=True, cwd=ROOT)
    if "No module named" in res.stderr:
        res = subprocess.run(["lint-imports", "--no-cache"], capture_output=True, text=True,
                             cwd=ROOT)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]


# --- import circles ------------------------------------------------------------------------

def import_graph(sources: dict[str, tuple[str, bool]]) -> dict[str, set[str]]:
    """Module -> the project modules it imports (at module level, under TYPE_CHECKING or in a
    function), for ``sources`` = {module: (source text, is a package)}. ``from pkg import x``
    is an import of the sub-module ``pkg.x`` when there is one, else of ``pkg`` (as grimp,
    behind import-linter, counts it)."""
    graph: dict[str, set[str]] = {name: set() for name in sources}
    for name, (source, is_package) in sources.items():
        targets: set[str] = set()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = from_base(node, name, is_package)
                targets |= {f"{base}.{a.name}" if f"{base}.{a.name}" in sources else base
                            for a in node.names}
        graph[name] = {t for t in targets if t in sources and t != name}
    return graph


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work: list[tuple[str, Iterator[str]]] = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            w = next(children, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def _a_cycle(graph: dict[str, set[str]], members: list[str]) -> list[str]:
    """One shortest circle through the first of ``members`` (a strongly connected set)."""
    start, inside = members[0], set(members)
    paths = {start: [start]}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v] & inside):
                if w == start:
                    return [*paths[v], start]
                if w not in paths:
                    paths[w] = [*paths[v], w]
                    nxt.append(w)
        frontier = nxt
    raise AssertionError(f"{members} is not strongly connected")


def import_cycles(sources: dict[str, tuple[str, bool]]) -> list[tuple[frozenset[str], str]]:
    """Every import circle: (the modules it joins, one circle as "a -> b -> a")."""
    graph = import_graph(sources)
    return [(frozenset(c), " -> ".join(_a_cycle(graph, c))) for c in _strongly_connected(graph)]


def project_sources() -> dict[str, tuple[str, bool]]:
    return {name: (path.read_text(encoding="utf-8"), path.name == "__init__.py")
            for name, path in project_modules()}


def test_the_cycle_checker_catches_circles():
    """A made-up circle is found and named (through a function-local import too); a
    sub-module imported from its package's name is not a circle."""
    circle = {"zrp.a": ("from zrp import b\n", False),
              "zrp.b": ("def f():\n    import zrp.c\n", False),
              "zrp.c": ("from zrp.a import thing\n", False),
              "zrp": ("", True)}
    assert import_cycles(circle) == [(frozenset({"zrp.a", "zrp.b", "zrp.c"}),
                                      "zrp.a -> zrp.b -> zrp.c -> zrp.a")]
    typed = {"zrp.m.budget": ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                              "    from zrp.m.reduction import Summary\n", False),
             "zrp.m.reduction": ("from zrp.m.budget import bound\n", False)}
    assert [c for _, c in import_cycles(typed)] == ["zrp.m.budget -> zrp.m.reduction -> "
                                                    "zrp.m.budget"]
    package = {"zrp.k": ("from zrp.k.forward import fk\n", True),
               "zrp.k.forward": ("from zrp.k import _kernels as K\n", False),
               "zrp.k._kernels": ("import numpy\n", False)}
    assert import_cycles(package) == []
    package["zrp.k.forward"] = ("from zrp.k import _kernels, helper\n", False)  # a name
    assert [c for _, c in import_cycles(package)] == ["zrp.k -> zrp.k.forward -> zrp.k"]


def test_no_import_circles():
    bad = [f"{chain}" for members, chain in import_cycles(project_sources())
           if not any(members <= allowed for allowed in CYCLE_ALLOWLIST)]
    assert not bad, "import circles:\n" + "\n".join(bad)


def test_cycle_allowlist_only_shrinks():
    """Each allow-listed circle is still there (else remove it from CYCLE_ALLOWLIST)."""
    found = [members for members, _ in import_cycles(project_sources())]
    gone = [sorted(allowed) for allowed in CYCLE_ALLOWLIST
            if not any(members <= allowed for members in found)]
    assert not gone, f"no longer circles, remove them from CYCLE_ALLOWLIST: {gone}"


# --- cyclomatic complexity (radon) ------------------------------------------------------------

def _functions(blocks: list, prefix: str = "") -> Iterator[tuple[str, int, int]]:
    """(qualified name, line, complexity) of every function, method and closure."""
    from radon.visitors import Class

    for block in blocks:
        if isinstance(block, Class):
            yield from _functions(block.inner_classes, f"{prefix}{block.name}.")
            continue
        name = prefix + (block.fullname if not prefix else block.name)
        yield name, block.lineno, block.complexity
        yield from _functions(block.closures, f"{name}.")


def complexities(source: str) -> dict[str, tuple[int, int]]:
    """{qualified function name: (line, radon cyclomatic complexity)} of one module."""
    # radon: the test extra installs it (pyproject.toml); this gate is its only user
    from radon.complexity import cc_visit

    return {name: (line, cc) for name, line, cc in _functions(cc_visit(source))}


def too_complex(source: str, limit: int = MAX_COMPLEXITY) -> dict[str, tuple[int, int]]:
    """The functions of ``source`` above ``limit``: {name: (line, complexity)}."""
    return {name: v for name, v in complexities(source).items() if v[1] > limit}


def project_complexities() -> dict[str, tuple[int, int]]:
    """{"path::function": (line, complexity)} over every module of zrp, mjcf and sim."""
    out = {}
    for _name, path in project_modules():
        rel = path.relative_to(ROOT).as_posix()
        for fn, v in complexities(path.read_text(encoding="utf-8")).items():
            out[f"{rel}::{fn}"] = v
    return out


def test_the_complexity_checker_counts_what_radon_counts():
    """A made-up function over the limit is caught by its `and`s alone (ruff's C901 gives it
    2); methods and closures are checked too; a function at the limit passes."""
    many = " and ".join(f"x{i}" for i in range(16))
    assert too_complex(f"def f():\n    if {many}:\n        return 1\n") == {"f": (1, 17)}
    ifs = "".join(f"    if x == {i}:\n        return {i}\n" for i in range(14))
    at_limit = f"def f(x):\n{ifs}    return -1\n"
    assert complexities(at_limit)["f"][1] == MAX_COMPLEXITY and not too_complex(at_limit)
    over = ifs + "    if x == 99:\n        return 99\n"
    nested = f"class A:\n    def m(self, x):\n        def g(x):\n{_indent(over, 8)}"
    assert set(too_complex(nested)) == {"A.m.g"}
    assert set(too_complex(f"class A:\n    def m(self, x):\n{_indent(over, 4)}")) == {"A.m"}


def _indent(text: str, n: int) -> str:
    return "".join(" " * n + line + "\n" for line in text.splitlines())


def test_no_function_above_complexity_15():
    """radon's cyclomatic complexity of every function of zrp, mjcf and sim is at most 15
    (split a longer one into named steps); COMPLEXITY_ALLOWLIST holds the exceptions being
    split elsewhere."""
    bad = [f"{key} (line {line}): complexity {cc} > {MAX_COMPLEXITY}"
           for key, (line, cc) in sorted(project_complexities().items())
           if cc > MAX_COMPLEXITY and key not in COMPLEXITY_ALLOWLIST]
    assert not bad, "functions above radon complexity 15:\n" + "\n".join(bad)


def test_complexity_allowlist_only_shrinks():
    """Every allow-listed function is in sim/ or zrp/gap/, still exists and is still above
    the limit: once split it leaves the list."""
    found = project_complexities()
    stale = [f"{key}: " + ("gone" if key not in found else f"now {found[key][1]}")
             for key in sorted(COMPLEXITY_ALLOWLIST)
             if key not in found or found[key][1] <= MAX_COMPLEXITY]
    stale += [f"{key}: outside {ALLOWLIST_FOLDERS}" for key in sorted(COMPLEXITY_ALLOWLIST)
              if not key.startswith(ALLOWLIST_FOLDERS)]
    assert not stale, "remove from COMPLEXITY_ALLOWLIST:\n" + "\n".join(stale)
