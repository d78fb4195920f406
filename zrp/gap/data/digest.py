"""The SHA-256 of a set of measurements as read (:func:`measurements_sha256`): what a stored
diagnosis records so that it is never reused on other data
(:mod:`zrp.gap.finalrecord`)."""

from __future__ import annotations

import hashlib

import numpy as np

from zrp.gap.data.measurements import Measurements

__all__ = ["measurements_sha256"]

#: the arrays hashed, in order (None marks one the data do not carry)
_ARRAYS = ("q", "xyz", "t", "temp", "load", "quat", "direction")


def measurements_sha256(meas: Measurements) -> str:
    """SHA-256 of the measurements' content: the frame, the pose ids and point labels row by
    row, and every numeric column as little-endian float64 (joint values in rad or the length
    unit, as the reader converted them), in row order; not the source name, so the same data
    read from a copy of the file hash alike."""
    h = hashlib.sha256()
    h.update(f"zrp measurements v1|{meas.frame}|".encode())
    for labels in (meas.pose, meas.point):
        h.update("\x1f".join(str(x) for x in labels).encode("utf-8") + b"\x1e")
    for name in _ARRAYS:
        arr = getattr(meas, name)
        h.update(name.encode() + b"=")
        if arr is None:
            h.update(b"none;")
        else:
            a = np.ascontiguousarray(np.asarray(arr, dtype="<f8"))
            h.update(str(a.shape).encode() + a.tobytes() + b";")
    return h.hexdigest()
