"""The report of a diagnosis, plain functions of the result: the verdict in plain words
(:func:`verdict_text`), the diagnosis.json document with it (:func:`diagnosis_document`),
report.md (:func:`report_markdown`), the plots, and the writer of the output folder
(:func:`write_outputs`). It reads the engine's results; the engine never imports it."""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "report_markdown": "zrp.gap.report.markdown",
    "implicated_joint": "zrp.gap.report.plots",
    "verdict_text": "zrp.gap.report.verdict",
    "OUTPUT_FILES": "zrp.gap.report.write",
    "diagnosis_document": "zrp.gap.report.write",
    "residuals_csv": "zrp.gap.report.write",
    "write_outputs": "zrp.gap.report.write",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.gap.report.markdown import report_markdown as report_markdown
    from zrp.gap.report.plots import implicated_joint as implicated_joint
    from zrp.gap.report.verdict import verdict_text as verdict_text
    from zrp.gap.report.write import OUTPUT_FILES as OUTPUT_FILES
    from zrp.gap.report.write import diagnosis_document as diagnosis_document
    from zrp.gap.report.write import residuals_csv as residuals_csv
    from zrp.gap.report.write import write_outputs as write_outputs

__all__ = [
    "OUTPUT_FILES",
    "diagnosis_document",
    "implicated_joint",
    "report_markdown",
    "residuals_csv",
    "verdict_text",
    "write_outputs",
]
