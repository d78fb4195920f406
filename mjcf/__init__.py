"""MJCF models of ZRP manipulators (built with mujoco.MjSpec) and import from MJCF/URDF."""
