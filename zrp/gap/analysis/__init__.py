"""Stage 4 of the diagnosis, judging data and fits: the checks that refuse or warn
(:mod:`.checks`), where the residual lies (:mod:`.where`), which joints the data excite
(:mod:`.excitation`), what the data can identify (:mod:`.identifiability`), the complete
geometric calibration beside the search (:mod:`.baseline`), the choice of the final model
(:mod:`.fallback`), how far to trust it (:mod:`.assessment`), whether what remains is
structured (:mod:`.structure`, on the regression of :mod:`.kernel`) and a learned residual
term that must earn its place (:mod:`.residual`). Imports only earlier stages.
"""
