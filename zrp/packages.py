"""The distribution's own top-level packages, and a clear error when another one shadows them.

The ``zrp-accuracy`` distribution installs three top-level packages side by side: ``zrp`` (the
core and the command line), ``mjcf`` and ``sim``. ``mjcf`` and ``sim`` are generic names that
another distribution, or a folder named ``sim`` in the current directory, may also provide;
whichever comes first on ``sys.path`` wins, and the loser's importers would then fail with an
obscure ``ImportError`` deep inside. Each of our packages carries ``__distribution__ =
"zrp-accuracy"``, and :func:`check_own_packages` (run by the command line before it imports
``mjcf`` or ``sim``, and by ``sim`` before it imports ``mjcf``) finds where each name would be
imported from, without importing it, and names the shadowing folder.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from zrp.errors import ZRPError

__all__ = ["DISTRIBUTION", "OWN_PACKAGES", "PackageShadowedError", "check_own_packages"]

#: The distribution that installs zrp, mjcf and sim.
DISTRIBUTION = "zrp-accuracy"
#: Its top-level packages besides zrp, installed in the same folder as zrp.
OWN_PACKAGES = ("mjcf", "sim")


class PackageShadowedError(ZRPError, ImportError):
    """Another ``mjcf`` or ``sim`` package comes before ours on ``sys.path`` (names both)."""


def _home() -> Path:
    """The folder holding this distribution's packages (site-packages, or the checkout)."""
    return Path(__file__).resolve().parent.parent


def check_own_packages(names: tuple[str, ...] = OWN_PACKAGES) -> None:
    """Check that each of ``names`` would be imported from this distribution's own folder.

    Raises:
        PackageShadowedError: a package of that name is missing from the distribution or
            another one (another distribution's, or a folder in the current directory) comes
            first on ``sys.path``; the message names both places and what to do.
    """
    home = _home()
    for name in names:
        spec = importlib.util.find_spec(name)
        origin = Path(spec.origin).resolve() if spec is not None and spec.origin else None
        if origin is not None and origin.name == "__init__.py" and origin.parent.parent == home:
            continue
        found = (f"the package {name!r} found first on sys.path is {origin.parent}"
                 if origin is not None else
                 f"no importable package {name!r} was found (a namespace folder or none)")
        raise PackageShadowedError(
            f"{DISTRIBUTION}'s own {name!r} package should be imported from {home / name}, "
            f"but {found}: another distribution or a folder named {name!r} (in the current "
            f"directory or on PYTHONPATH) shadows it. Uninstall or rename that package, or run "
            f"from another directory (see README.md, 'Package names').")
