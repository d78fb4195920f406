"""The layer contract, module size and the import-order independence of the public API.

Layers, lowest first: the core ``zrp`` (everything but ``zrp.cli``) -> ``mjcf`` -> ``sim`` ->
the command line ``zrp.cli``. A module never imports a layer above its own; the core uses only
the standard library, NumPy, SciPy, numba and tqdm (Matplotlib only in report and plot
modules); no engine module imports a report module. The same contract runs in CI through
import-linter (``[tool.importlinter]`` in pyproject.toml); this test also covers what
import-linter cannot express (third-party allow-lists, report modules, function-local imports).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("zrp", "mjcf", "sim")
LAYER = {"core": 0, "mjcf": 1, "sim": 2, "cli": 3}
# threadpoolctl: BLAS thread limits for the diagnosis (zrp/blas.py)
CORE_THIRD_PARTY = {"numpy", "scipy", "numba", "tqdm", "tomli", "threadpoolctl"}
REPORT_ONLY = {"matplotlib", "PIL"}
MAX_LINES = 400


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
            base = node.module or ""
            if node.level:
                pkg = module.split(".") if is_package else module.split(".")[:-1]
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join([*pkg, base] if base else pkg)
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
    assert violations("zrp.kinematics.forward", "def f():\n    import sim.playback\n")
    assert violations("zrp.gap.pipeline", "from mjcf import build\n")
    assert violations("zrp.model.files", "from zrp.cli.app import emit\n")
    assert violations("mjcf.builder", "import sim\n")
    assert violations("sim.video", "from zrp.cli import main\n")
    assert violations("zrp.gap.analysis.where", "import matplotlib.pyplot as plt\n")
    assert violations("zrp.gap.analysis.where", "import pandas\n")
    assert violations("zrp.gap.pipeline", "from zrp.gap.report.write import write_outputs\n")
    assert violations("zrp.gap.analysis.where", "from ..report import plots\n")
    # and lets the allowed ones through
    assert not violations("zrp.gap.report.plots", "import matplotlib\n")
    assert not violations("sim.video", "import mjcf\nimport mujoco\nimport zrp\n")
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
