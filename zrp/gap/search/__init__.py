"""Stage 5 of the diagnosis, the effect search: the greedy forward search with its backward
pass (:mod:`.greedy`), what each step records (:mod:`.steps`), the refit with measured
orientations and its orientation search (:mod:`.posefit`, :mod:`.posesearch`) and the progress
display (:mod:`.progress`). Imports only earlier stages; :mod:`zrp.gap.pipeline` runs it.
"""
