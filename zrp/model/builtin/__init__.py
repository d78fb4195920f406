"""Model files shipped with the package (see :func:`zrp.builtin_models`)."""
