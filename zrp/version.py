"""The toolkit's version, the one place it is written: ``pyproject.toml`` reads it from here
(``[tool.setuptools.dynamic]``), ``zrp --version`` prints it, and every file a later step reads
(diagnosis.json, calibrated.toml, compensation.json, compensated commands) records it."""

__all__ = ["__version__"]

__version__ = "0.5.0"
