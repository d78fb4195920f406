"""Checks ``MUJOCO_GL`` before the ``mjcf`` package imports MuJoCo (which fails on a bad value
with a bare RuntimeError). Imported first by ``mjcf/__init__.py`` (its name sorts first)."""

from zrp.environment import check_mujoco_gl

check_mujoco_gl()
