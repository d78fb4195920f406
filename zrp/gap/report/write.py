"""Write a :class:`~zrp.gap.Diagnosis` to a folder: diagnosis.json (:func:`diagnosis_document`:
the result's JSON with the verdict), residuals.csv, the PNG plots, report.md and report.html (the
same text with the figures embedded), through the one output policy (:mod:`zrp.output`)."""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from zrp.escape import csv_text
from zrp.gap.report.html import report_html
from zrp.gap.report.markdown import report_markdown
from zrp.gap.report.plots import DPI, PLOT_FILES, figures, withheld_rows
from zrp.gap.report.verdict import verdict_text
from zrp.gap.results import Diagnosis
from zrp.output import OutputDir
from zrp.version import __version__

__all__ = ["OUTPUT_FILES", "diagnosis_document", "residuals_csv", "write_outputs"]

#: every file :func:`write_outputs` writes (all are checked, even without plots, so that no
#: plot of an earlier run is left beside the new results).
OUTPUT_FILES = ("diagnosis.json", "report.md", "report.html", "residuals.csv", *PLOT_FILES)


def diagnosis_document(diag: Diagnosis) -> dict[str, Any]:
    """The diagnosis.json document: the toolkit's version (``zrp_version``), then
    :meth:`Diagnosis.to_dict` with the verdict in plain words (:func:`verdict_text`) after
    ``unexplained``."""
    out: dict[str, Any] = {"zrp_version": __version__}
    for key, value in diag.to_dict().items():
        out[key] = value
        if key == "unexplained":
            out["verdict"] = verdict_text(diag)
    return out


def residuals_csv(diag: Diagnosis) -> str:
    """The withheld residuals before and after the corrections, one row per measured point
    with its source line."""
    meas = diag.context.meas
    rb = diag.withheld_residual_before.reshape(-1, 3)
    ra = diag.withheld_residual_after.reshape(-1, 3)
    rows = ([int(meas.lines[r]), meas.pose[r], meas.point[r],
             *(f"{v:.6g}" for v in rb[i]), f"{np.linalg.norm(rb[i]):.6g}",
             *(f"{v:.6g}" for v in ra[i]), f"{np.linalg.norm(ra[i]):.6g}"]
            for i, r in enumerate(withheld_rows(diag)))
    return csv_text(["line", "pose", "point", "before_x", "before_y", "before_z",
                     "before_norm", "after_x", "after_y", "after_z", "after_norm"], rows)


def _write(diag: Diagnosis, out: OutputDir, plots: bool) -> list[Path]:
    first = len(out.written)
    out.write_json("diagnosis.json", diagnosis_document(diag))
    out.write_text("residuals.csv", residuals_csv(diag))
    svgs: dict[str, bytes] = {}
    if plots:
        for name, fig in figures(diag):
            out.savefig(name, fig, dpi=DPI)
            buf = io.BytesIO()
            fig.savefig(buf, format="svg", dpi=DPI)
            svgs[name] = buf.getvalue()
    md = report_markdown(diag, figures=plots)
    out.write_text("report.md", md)
    out.write_text("report.html", report_html(md, svgs, f"Gap diagnosis: {diag.model_name}"))
    return out.written[first:]


def write_outputs(diag: Diagnosis, out_dir: str | os.PathLike[str] | OutputDir, *,
                  overwrite: bool = False, plots: bool = True) -> list[Path]:
    """Write diagnosis.json, residuals.csv, (with ``plots``) the PNGs, report.md and
    report.html.

    Args:
        out_dir: the folder, or an :class:`~zrp.output.OutputDir` the caller has entered
            (then its own ``overwrite`` policy applies, and it should have checked
            :data:`OUTPUT_FILES` on entry).
        overwrite: replace files that exist (for a folder path); the plots of an earlier
            run are removed when this one makes none (``prune``, :class:`~zrp.output.OutputDir`).

    Returns:
        the paths written, in order.

    Raises:
        OutputExistsError: one of :data:`OUTPUT_FILES` exists and ``overwrite`` is False
            (nothing is written then).
        OutputBusyError: another run is writing into the folder.
    """
    if isinstance(out_dir, OutputDir):
        return _write(diag, out_dir, plots)
    with OutputDir(out_dir, overwrite=overwrite, names=OUTPUT_FILES, prune=True) as out:
        return _write(diag, out, plots)
