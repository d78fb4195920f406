"""Stage 3 of the diagnosis, fitting a corrected model: weighted least squares with
identifiability checks, cross-validation and F tests (:mod:`.leastsq`), error metrics
(:mod:`.metrics`), the registration as reported (:mod:`.registration`), robust intervals
(:mod:`.uncertainty`), the full-pose fit with orientations (:mod:`.fullpose`) and the profiled
nonlinear parameters (:mod:`.profiles`). Imports only the model and data stages.
"""
