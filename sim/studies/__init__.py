"""Studies on the physics robot: the blind benchmarks of the gap diagnosis
(:mod:`.benchmark`: static scenarios, in motion, the compensated column), the K-planned-poses
study (:mod:`.planning`) and the compensation check (:mod:`.compensation_check`).

Nothing is imported here: ``from sim.studies.benchmark import run_benchmark``.
"""
