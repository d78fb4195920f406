"""One home for each basic: the array aliases live in zrp.arrays only, and conversions are
named ``X_from_Y`` (pytransform3d's style: ``matrix_from_er``, not ``er_to_matrix``)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.contracts.test_architecture import ROOT, project_modules

ALIASES = {"F64", "I64", "U8"}
# a conversion written the other way round: <thing>_to_<thing>, e.g. er_to_matrix, deg_to_rad
TO_STYLE = re.compile(r"^[a-z0-9]+_to_(matrix|rotvec|er|quat|scipy_quat|rad|deg|mm|m|axis_angle)$")


def _modules() -> list[Path]:
    return [path for _, path in project_modules()]


def alias_definitions(source: str) -> list[str]:
    """Module-level assignments of an array alias name (F64 = ...)."""
    return [t.id for node in ast.parse(source).body if isinstance(node, ast.Assign)
            for t in node.targets if isinstance(t, ast.Name) and t.id in ALIASES]


def to_style_functions(source: str) -> list[str]:
    """Public functions named the X_to_Y way round."""
    return [n.name for n in ast.walk(ast.parse(source))
            if isinstance(n, ast.FunctionDef) and TO_STYLE.match(n.name)]


def test_the_checks_can_fail():
    assert alias_definitions("import numpy as np\nF64 = NDArray[np.float64]\n") == ["F64"]
    assert not alias_definitions("from zrp.arrays import F64\n")
    assert to_style_functions("def er_to_matrix(e):\n    pass\n") == ["er_to_matrix"]
    assert not to_style_functions("def matrix_from_er(e):\n    pass\n")


def test_array_aliases_have_one_home():
    bad = [f"{p.relative_to(ROOT)}: {name}" for p in _modules()
           if p.relative_to(ROOT).as_posix() != "zrp/arrays.py"
           for name in alias_definitions(p.read_text(encoding="utf-8"))]
    assert not bad, f"import the array aliases from zrp.arrays instead of defining them: {bad}"


def test_conversions_are_named_x_from_y():
    bad = [f"{p.relative_to(ROOT)}: {name}" for p in _modules()
           for name in to_style_functions(p.read_text(encoding="utf-8"))]
    assert not bad, f"name conversions X_from_Y (pytransform3d style): {bad}"
