"""Stage 2 of the diagnosis, the corrected model: the parameters and the data context
(:mod:`.context`), the effect library (:mod:`.effects`), the bases of its joint corrections
(:mod:`.jointbases`) and the residual with its analytic Jacobian (:mod:`.problem`). Imports only
the data stage.
"""
