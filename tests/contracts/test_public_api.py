"""The public API does not depend on import order: explicit re-exports, and no sub-module that
shares a name with a function or class its package exports."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("zrp", "mjcf", "sim")


def all_modules() -> list[str]:
    names = []
    for top in PACKAGES:
        pkg = importlib.import_module(top)
        names.append(top)
        names += [m.name for m in pkgutil.walk_packages(pkg.__path__, f"{top}.")
                  if not m.name.endswith("__main__")]
    return sorted(names)


def test_no_submodule_shares_a_name_with_an_export():
    clashes = []
    for name in all_modules():
        mod = importlib.import_module(name)
        if not hasattr(mod, "__path__"):
            continue
        subs = {m.name for m in pkgutil.iter_modules(mod.__path__)}
        clashes += [f"{name}.{s}" for s in subs & set(getattr(mod, "__all__", ()))]
    assert not clashes, f"sub-modules named like an export: {clashes}"


def test_no_module_is_named_like_a_function_it_holds():
    """`zrp.gap.diagnose` the module once hid `diagnose` the function: no module may hold a
    function, class or constant of its own name."""
    clashes = []
    for name in all_modules():
        mod = importlib.import_module(name)
        base = name.rsplit(".", 1)[-1]
        obj = getattr(mod, base, None)
        if obj is not None and not isinstance(obj, types.ModuleType):
            clashes.append(name)
    assert not clashes, clashes


def test_exports_resolve_to_the_same_objects_whatever_was_imported_first():
    """In a fresh interpreter every sub-module is imported first (the order that used to turn
    `from zrp.gap import diagnose` into the module); then every exported name must still be
    the function/class/constant, never a module."""
    code = f"""
import importlib, pkgutil, types
mods = {all_modules()!r}
for m in reversed(mods):
    importlib.import_module(m)
bad = []
for m in mods:
    mod = importlib.import_module(m)
    for name in getattr(mod, "__all__", ()):
        obj = getattr(mod, name)
        if isinstance(obj, types.ModuleType):
            bad.append(f"{{m}}.{{name}}")
from zrp.gap import diagnose, load_measurements, write_outputs
assert callable(diagnose) and callable(load_measurements) and callable(write_outputs)
from sim import measure
assert callable(measure) and not isinstance(measure, types.ModuleType)
print(bad)
raise SystemExit(1 if bad else 0)
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-3000:]


def test_reported_import_order_case():
    """The case from the architecture issue, reproduced literally."""
    code = ("import zrp.gap.report\nfrom zrp.gap import diagnose\n"
            "from zrp.gap import load_measurements, write_outputs, diagnose\n"
            "import types\nassert not isinstance(diagnose, types.ModuleType), diagnose\n"
            "assert diagnose.__name__ == 'diagnose'\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stderr[-3000:]


def test_every_export_exists():
    missing = []
    for name in all_modules():
        mod = importlib.import_module(name)
        missing += [f"{name}.{n}" for n in getattr(mod, "__all__", ()) if not hasattr(mod, n)]
    assert not missing, missing


def test_top_level_api_is_explicit():
    """`zrp`'s names are imported on first use (zrp/lazy.py: `import zrp` and `zrp --help` do
    not load SciPy and numba), but explicitly: each name of ``__all__`` is listed in the lazy
    table with its defining module (and, for type checkers, imported under TYPE_CHECKING),
    resolves to that module's object, never to a module, and is then bound in ``vars(zrp)``;
    a name outside the table is an AttributeError, not a guess."""
    code = """
import importlib, types, zrp
assert set(zrp.__all__) - {"__version__"} <= set(zrp._LAZY) | set(vars(zrp)), "unlisted"
for name in zrp.__all__:
    obj = getattr(zrp, name)
    assert not isinstance(obj, types.ModuleType), name
    entry = zrp._LAZY.get(name)
    if entry is not None:
        mod, attr = (entry, name) if isinstance(entry, str) else entry
        assert obj is getattr(importlib.import_module(mod), attr), name
    assert name in vars(zrp), name
try:
    zrp.no_such_name
except AttributeError:
    pass
else:
    raise AssertionError("an unknown name resolved")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stderr[-3000:]
