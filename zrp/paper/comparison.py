"""Our study beside every published cell of Tables 2 and 3 (xi > 0), each with a status and
the reason for it: "match", "discrepancy", "typo" or "trajectory-dependent"."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zrp.errors import InputError
from zrp.manufacturing.study import StudyResult
from zrp.model.manipulator import Manipulator
from zrp.paper.published import (
    CELL_STATUSES,
    LIKELY_TYPOS,
    PUBLISHED_ROWS,
    PUBLISHED_TABLE2,
    PUBLISHED_TABLE3,
    half_ulp,
)

__all__ = ["Cell", "compare_with_published", "kind_columns", "table_value"]


def kind_columns(study: StudyResult, kind: str) -> list[str]:
    """The study's parameters of one kind, "LE" or "JE", in study order."""
    return [p for p in study.parameters if p.startswith(kind)]


@dataclass(frozen=True)
class Cell:
    """One published cell beside ours.

    Attributes:
        table: 2 or 3. column: e.g. "LE3". xi_percent: the row.
        ours, published: values (mm for Table 2, eq 15 for Table 3).
        ratio: ours / published.
        status: "match", "discrepancy", "typo" or "trajectory-dependent".
        note: the explanation.
    """

    table: int
    column: str
    xi_percent: float
    ours: float
    published: float
    ratio: float
    status: str
    note: str

    def __post_init__(self) -> None:
        if self.table not in (2, 3):
            raise InputError(f"Cell.table: expected 2 or 3, got {self.table!r}")
        if self.status not in CELL_STATUSES:
            raise InputError(f"Cell.status: expected one of {CELL_STATUSES}, got "
                             f"{self.status!r}")


def table_value(study: StudyResult, quantity: str, col: str, xi: float) -> float:
    """Max of ``quantity`` ("delta_p" or "delta_r") for column ``col`` at level ``xi`` (%)."""
    i = study.index(col)
    j = int(np.argmin(np.abs(study.xi_percent - xi)))
    if abs(study.xi_percent[j] - xi) > 1e-12:
        raise InputError(f"xi {xi} %: not a level of the study (levels {study.xi_percent})")
    data = study.max_delta_p if quantity == "delta_p" else study.max_delta_r
    return float(data[i, j])


def _je_on_recovered(cell: Cell) -> Cell:
    """A joint-axis cell of the study on the recovered circle: "match" to the printed digits,
    "reproduced" within 5 %, else it stays "trajectory-dependent" (typos are kept)."""
    if cell.status == "typo" or not cell.column.startswith("JE"):
        return cell
    if abs(cell.ours - cell.published) <= half_ulp(cell.published) * 1.0001:
        status, note = "match", "on the recovered circle, to the printed digits"
    elif abs(cell.ratio - 1.0) <= 0.05:
        status, note = "reproduced", (f"on the recovered circle, within {abs(cell.ratio - 1):.2%}"
                                      " (the printed digits allow "
                                      f"{half_ulp(cell.published) / cell.published:.2%})")
    else:
        return cell
    return Cell(cell.table, cell.column, cell.xi_percent, cell.ours, cell.published, cell.ratio,
                status, note)


def compare_with_published(study: StudyResult, model: Manipulator, *,
                           recovered: bool = False) -> list[Cell]:
    """Every published cell of Tables 2 and 3 (xi > 0) beside ours, with a status and reason.

    ``recovered``: the study ran on the circle recovered from the tables
    (:data:`zrp.paper.placement.RECOVERED`): joint-axis cells are then judged as matches.
    """
    cells = _compare(study, model)
    return [_je_on_recovered(c) for c in cells] if recovered else cells


def _compare(study: StudyResult, model: Manipulator) -> list[Cell]:
    cells: list[Cell] = []
    for col, vals in PUBLISHED_TABLE2.items():
        for xi, pub in zip(PUBLISHED_ROWS, vals, strict=True):
            ours = table_value(study, "delta_p", col, xi)
            ratio = ours / pub
            if (2, col, xi) in LIKELY_TYPOS:
                trend = LIKELY_TYPOS[(2, col, xi)]
                status = "typo"
                note = (f"printed {pub:.2E}; the column's other rows are linear in xi and give "
                        f"{trend:.2E} (a factor {trend / pub:g}); ours / trend = "
                        f"{ours / trend:.3f}")
            elif col.startswith("LE"):
                k = int(col[2:])
                length = float(np.linalg.norm(model.bodies[k - 1]))
                if abs(ours - pub) <= half_ulp(pub) * 1.0001:
                    status = "match"
                    note = (f"= xi * ||b_{k},0|| = {xi / 100:g} x {length:g} mm, to the printed "
                            "digits")
                else:
                    status = "discrepancy"
                    note = (f"published value implies ||b_{k},0|| = {pub / (xi / 100):.1f} mm, "
                            f"Table 1 gives {length:g} mm (ours = xi * ||b||, independent of the "
                            f"trajectory)")
            else:
                status = "trajectory-dependent"
                note = ("depends on the circle's placement and start configuration, which the "
                        "paper does not give")
            cells.append(Cell(2, col, xi, ours, pub, ratio, status, note))
    for col, vals in PUBLISHED_TABLE3.items():
        for xi, pub in zip(PUBLISHED_ROWS, vals, strict=True):
            ours = table_value(study, "delta_r", col, xi)
            cells.append(Cell(3, col, xi, ours, pub, ours / pub, "trajectory-dependent",
                              "max eq (15) = f(max_t |sin(q_k/2)|): the paper's joints turned "
                              "further than ours (see implied joint angles)"))
    return cells
