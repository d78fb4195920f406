"""The paper's published Tables 2 and 3 as data, as printed (including two likely typos), and
what Table 3 implies about the paper's unpublished trajectory (:func:`implied_joint_angles`).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "CELL_STATUSES",
    "JE_PARAMS",
    "LE_PARAMS",
    "LIKELY_TYPOS",
    "PUBLISHED_ROWS",
    "PUBLISHED_TABLE2",
    "PUBLISHED_TABLE2_ZERO",
    "PUBLISHED_TABLE3",
    "PUBLISHED_TABLE3_ZERO",
    "half_ulp",
    "implied_joint_angles",
]

#: xi (percent) of the published rows 2-5 of Tables 2 and 3.
PUBLISHED_ROWS: tuple[float, ...] = (0.02, 0.05, 0.07, 0.1)
#: Table 2: maximum positional deviations (mm), as printed (including the two likely typos).
PUBLISHED_TABLE2: dict[str, tuple[float, ...]] = {
    "LE2": (5.08e-2, 1.27e-1, 1.78e-1, 2.54e-1),
    "LE3": (8.89e-2, 2.22e-1, 3.11e-1, 4.44e-1),
    "LE4": (8.64e-2, 2.16e-1, 3.02e-1, 4.32e-1),
    "LE7": (2.54e-2, 6.35e-2, 8.89e-2, 1.27e-1),
    "JE1": (1.58e-1, 3.94e-1, 5.52e-1, 7.88e0),
    "JE2": (2.66e-1, 6.65e-1, 9.31e-1, 1.33e-1),
    "JE3": (1.79e-1, 4.47e-1, 6.26e-1, 8.94e-1),
    "JE4": (7.05e-2, 1.76e-1, 2.47e-1, 3.52e-1),
    "JE5": (5.99e-2, 1.50e-1, 2.09e-1, 2.99e-1),
    "JE6": (7.18e-2, 1.80e-1, 2.51e-1, 3.59e-1),
}
#: Table 2, 0 % row (one value for all columns), mm.
PUBLISHED_TABLE2_ZERO = 1.07e-8
#: Table 3: maximum rotational deviations, eq (15) (dimensionless), as printed.
PUBLISHED_TABLE3: dict[str, tuple[float, ...]] = {
    "JE1": (7.98e-4, 1.99e-3, 2.79e-3, 3.99e-3),
    "JE2": (7.65e-4, 1.91e-3, 2.68e-3, 3.82e-3),
    "JE3": (7.68e-4, 1.92e-3, 2.69e-3, 3.84e-3),
    "JE4": (8.00e-4, 2.00e-3, 2.80e-3, 4.00e-3),
    "JE5": (6.88e-4, 1.72e-3, 2.41e-3, 3.44e-3),
    "JE6": (8.00e-4, 2.00e-3, 2.80e-3, 4.00e-3),
}
#: Table 3, 0 % row.
PUBLISHED_TABLE3_ZERO = 5.96e-8
#: Cells that look like typos: (table, column, xi) -> value the column's trend implies.
LIKELY_TYPOS: dict[tuple[int, str, float], float] = {
    (2, "JE1", 0.1): 7.88e-1,
    (2, "JE2", 0.1): 1.33e0,
}
#: "reproduced": a joint-axis cell within 5 % (not to the printed digits) on the circle
#: recovered from the tables (:data:`zrp.paper.placement.RECOVERED`).
CELL_STATUSES = ("match", "discrepancy", "typo", "trajectory-dependent", "reproduced")
LE_PARAMS = ("LE2", "LE3", "LE4", "LE7")
JE_PARAMS = ("JE1", "JE2", "JE3", "JE4", "JE5", "JE6")



def half_ulp(value: float, digits: int = 3) -> float:
    """Half a unit in the last printed digit of a value printed with ``digits`` digits."""
    if value == 0:
        return 0.0
    return 0.5 * 10.0 ** (np.floor(np.log10(abs(value))) - (digits - 1))


def implied_joint_angles(table3: dict[str, tuple[float, ...]] | None = None,
                         rows: tuple[float, ...] = PUBLISHED_ROWS) -> dict[str, dict[str, float]]:
    """Max |q_k| (deg) that the published Table 3 implies for the paper's trajectory.

    With sign(0) = +1, JE_k tilts u_k by alpha = atan(sqrt(2) xi / (1 + xi)); turned by q_k, the
    error rotation has sin(theta/4) = |sin(q_k/2)| sin(alpha/2), and eq (15) gives
    delta_R = 2 sqrt(2) sin(theta/2). Inverting each printed cell (3 digits) gives an estimate;
    the spread over the four rows and the printed rounding give its range. A ratio at or above
    1 means |q_k| reached 180 deg (within the rounding).
    """
    table3 = PUBLISHED_TABLE3 if table3 is None else table3
    out: dict[str, dict[str, float]] = {}
    for col, vals in table3.items():
        est = []
        for xi, v in zip(rows, vals, strict=True):
            x = xi / 100.0
            alpha = np.arctan(np.sqrt(2.0) * x / (1.0 + x))
            for vv in (v - half_ulp(v), v, v + half_ulp(v)):
                theta = 2.0 * np.arcsin(min(vv / np.sqrt(8.0), 1.0))
                r = np.sin(theta / 4.0) / np.sin(alpha / 2.0)
                est.append(np.degrees(2.0 * np.arcsin(min(r, 1.0))))
        out[col] = {"deg_min": float(min(est)), "deg_max": float(max(est))}
    return out


#: Readings of ||b_3|| (mm) that Table 1 or the PUMA 560 literature could give: (name, mm).
LE3_READINGS: tuple[tuple[str, float], ...] = (
    ("Table 1 as printed: b_3 = (431.8, 0, 0) = 17 in", 431.8),
    ("PUMA 560 d4 = 433.07 mm (17.05 in, Craig; the '433 mm' of the literature)", 433.07),
    ("431.8 mm with the PUMA 560 forearm offset a3 = 20.32 mm (0.8 in) at right angles",
     float(np.hypot(431.8, 20.32))),
    ("433.07 mm with a3 = 20.32 mm at right angles", float(np.hypot(433.07, 20.32))),
    ("431.8 mm plus a3 = 20.32 mm along the link", 431.8 + 20.32),
    ("431.8 mm with the PUMA 560 shoulder offset d3 = 149.09 mm at right angles",
     float(np.hypot(431.8, 149.09))),
    ("431.8 mm with the tool length 127 mm at right angles", float(np.hypot(431.8, 127.0))),
    ("17.5 in = 444.5 mm (17 in misread or mistyped by half an inch)", 17.5 * 25.4),
)


def le3_readings() -> list[dict[str, object]]:
    """Each :data:`LE3_READINGS` entry beside the published LE3 column: the cells xi ||b_3||
    it predicts and how many of the four equal the printed value to its 3 digits."""
    out: list[dict[str, object]] = []
    pub = PUBLISHED_TABLE2["LE3"]
    for name, length in LE3_READINGS:
        pred = [x / 100.0 * length for x in PUBLISHED_ROWS]
        hits = sum(abs(p - v) <= half_ulp(v) * 1.0001 for p, v in zip(pred, pub, strict=True))
        out.append({"reading": name, "b3_mm": round(length, 2), "predicted": pred,
                    "cells_matching": int(hits)})
    return out
