"""Seeing a simulation: MuJoCo kinematic playback and its check against ZRP
(:mod:`.playback`), the GL backend and the offscreen renderer (:mod:`.gl`, :mod:`.render`),
camera framing (:mod:`.framing`), comparison frames of a nominal and a perturbed arm
(:mod:`.frames`, with :mod:`.overlays` and :mod:`.magnify`) and their videos (:mod:`.video`),
the video of a motion diagnosis (:mod:`.motion_video`) and the interactive viewer
(:mod:`.viewer`).

Nothing is imported here: :mod:`sim.view.gl` must be importable without MuJoCo, so that the
backend can be chosen before MuJoCo's first import.
"""
