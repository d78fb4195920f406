"""Stage 1 of the diagnosis, the data: measured points per pose (:mod:`.measurements`), the CSV
reader (:mod:`.csvfile`; its header and records: :mod:`.csvrows`), the pose subsample for large
files (:mod:`.subsample`), the split into fitting and withheld poses (:mod:`.split`), the noise
floor (:mod:`.noise`) and synthetic data with known injected effects (:mod:`.synthetic`).
Imports no other stage.
"""
