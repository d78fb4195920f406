"""The physics "real" robot and its instrument: hidden effects (:mod:`.effects`, their text
specs :mod:`.effect_specs`), the robot's MuJoCo model (:mod:`.model`), its mass model (the
arm's own or an announced fallback, :mod:`.mass`) and servo tuning (:mod:`.servo`), the
robot with its controller at rest (:mod:`.real`) and in motion (:mod:`.motion`), servo
dynamics along a joint trajectory (:mod:`.dynamics`), the laser tracker (:mod:`.instrument`)
and the measuring procedures: poses at rest (:mod:`.measurement`) and streams in motion
(:mod:`.motion_measure`).

The trajectories a robot is measured along are passed in by the caller (the studies and the
command line build the paper's circle); this package imports neither the paper nor the
other sub-packages of :mod:`sim`. Nothing is imported here.
"""
