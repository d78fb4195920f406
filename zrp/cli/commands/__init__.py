"""Subcommands of ``zrp``: each module defines ``register(subparsers)`` (see zrp.cli.app)."""
