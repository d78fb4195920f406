"""Model files shipped with the package (see :func:`zrp.builtin_models`)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["builtin_models"]


def builtin_models() -> dict[str, Path]:
    """Model files shipped with the package, by short name (e.g. ``"puma"``)."""
    root = resources.files("zrp.model.builtin")
    return {Path(str(f)).stem: Path(str(f)) for f in root.iterdir() if str(f).endswith(".toml")}
