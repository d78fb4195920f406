"""MuJoCo playback, consistency checks and offscreen rendering of ZRP manipulators."""
