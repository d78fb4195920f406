"""The paper's numerical example as a scenario: the Table 1 PUMA drawing a 125 mm circle
(:mod:`.scenario`), its perturbation study (:mod:`.example`), the published Tables 2-3 as data
(:mod:`.published`), the comparison with them (:mod:`.comparison`), the paper's claims checked
(:mod:`.claims`), and the outputs: tables, report and JSON (:mod:`.report`), Figures 2-7
(:mod:`.figures`), the scenes of its videos (:mod:`.scenes`), the circle recovered from the
published tables (:mod:`.placement`, :mod:`.inverse`, :mod:`.circles`) and the renders/ index
page (:mod:`.index`). See README.md in this folder.
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "check_claims": "zrp.paper.claims",
    "Cell": "zrp.paper.comparison",
    "compare_with_published": "zrp.paper.comparison",
    "kind_columns": "zrp.paper.comparison",
    "table_value": "zrp.paper.comparison",
    "PaperExample": "zrp.paper.example",
    "default_parameters": "zrp.paper.example",
    "run_paper_example": "zrp.paper.example",
    "write_index": "zrp.paper.index",
    "CellFit": "zrp.paper.inverse",
    "RecoveryResult": "zrp.paper.inverse",
    "fit_cells": "zrp.paper.inverse",
    "local_pinning": "zrp.paper.inverse",
    "recover_circle": "zrp.paper.inverse",
    "DEFAULT_PLACEMENT": "zrp.paper.placement",
    "RECOVERED": "zrp.paper.placement",
    "CirclePlacement": "zrp.paper.placement",
    "placement_path": "zrp.paper.placement",
    "CELL_STATUSES": "zrp.paper.published",
    "JE_PARAMS": "zrp.paper.published",
    "LE_PARAMS": "zrp.paper.published",
    "LIKELY_TYPOS": "zrp.paper.published",
    "PUBLISHED_ROWS": "zrp.paper.published",
    "PUBLISHED_TABLE2": "zrp.paper.published",
    "PUBLISHED_TABLE2_ZERO": "zrp.paper.published",
    "PUBLISHED_TABLE3": "zrp.paper.published",
    "PUBLISHED_TABLE3_ZERO": "zrp.paper.published",
    "half_ulp": "zrp.paper.published",
    "implied_joint_angles": "zrp.paper.published",
    "le3_readings": "zrp.paper.published",
    "comparison_csv": "zrp.paper.report",
    "comparison_markdown": "zrp.paper.report",
    "output_names": "zrp.paper.report",
    "paper_summary": "zrp.paper.report",
    "write_paper_outputs": "zrp.paper.report",
    "PUMA_DURATION_S": "zrp.paper.scenario",
    "PUMA_Q0_DEG": "zrp.paper.scenario",
    "PUMA_RADIUS_MM": "zrp.paper.scenario",
    "CircleSetup": "zrp.paper.scenario",
    "circle_joint_path": "zrp.paper.scenario",
    "is_paper_model": "zrp.paper.scenario",
    "paper_start": "zrp.paper.scenario",
    "puma_circle": "zrp.paper.scenario",
    "puma_circle_ik": "zrp.paper.scenario",
    "PAPER_LEVELS": "zrp.paper.scenes",
    "Scene": "zrp.paper.scenes",
    "SceneSegment": "zrp.paper.scenes",
    "paper_magnification": "zrp.paper.scenes",
    "paper_video_file_name": "zrp.paper.scenes",
    "paper_video_scene": "zrp.paper.scenes",
    "perturbed_puma": "zrp.paper.scenes",
    "teaching_sweep_scene": "zrp.paper.scenes",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.paper.claims import check_claims as check_claims
    from zrp.paper.comparison import Cell as Cell
    from zrp.paper.comparison import compare_with_published as compare_with_published
    from zrp.paper.comparison import kind_columns as kind_columns
    from zrp.paper.comparison import table_value as table_value
    from zrp.paper.example import PaperExample as PaperExample
    from zrp.paper.example import default_parameters as default_parameters
    from zrp.paper.example import run_paper_example as run_paper_example
    from zrp.paper.index import write_index as write_index
    from zrp.paper.inverse import CellFit as CellFit
    from zrp.paper.inverse import RecoveryResult as RecoveryResult
    from zrp.paper.inverse import fit_cells as fit_cells
    from zrp.paper.inverse import local_pinning as local_pinning
    from zrp.paper.inverse import recover_circle as recover_circle
    from zrp.paper.placement import DEFAULT_PLACEMENT as DEFAULT_PLACEMENT
    from zrp.paper.placement import RECOVERED as RECOVERED
    from zrp.paper.placement import CirclePlacement as CirclePlacement
    from zrp.paper.placement import placement_path as placement_path
    from zrp.paper.published import CELL_STATUSES as CELL_STATUSES
    from zrp.paper.published import JE_PARAMS as JE_PARAMS
    from zrp.paper.published import LE_PARAMS as LE_PARAMS
    from zrp.paper.published import LIKELY_TYPOS as LIKELY_TYPOS
    from zrp.paper.published import PUBLISHED_ROWS as PUBLISHED_ROWS
    from zrp.paper.published import PUBLISHED_TABLE2 as PUBLISHED_TABLE2
    from zrp.paper.published import PUBLISHED_TABLE2_ZERO as PUBLISHED_TABLE2_ZERO
    from zrp.paper.published import PUBLISHED_TABLE3 as PUBLISHED_TABLE3
    from zrp.paper.published import PUBLISHED_TABLE3_ZERO as PUBLISHED_TABLE3_ZERO
    from zrp.paper.published import half_ulp as half_ulp
    from zrp.paper.published import implied_joint_angles as implied_joint_angles
    from zrp.paper.published import le3_readings as le3_readings
    from zrp.paper.report import comparison_csv as comparison_csv
    from zrp.paper.report import comparison_markdown as comparison_markdown
    from zrp.paper.report import output_names as output_names
    from zrp.paper.report import paper_summary as paper_summary
    from zrp.paper.report import write_paper_outputs as write_paper_outputs
    from zrp.paper.scenario import PUMA_DURATION_S as PUMA_DURATION_S
    from zrp.paper.scenario import PUMA_Q0_DEG as PUMA_Q0_DEG
    from zrp.paper.scenario import PUMA_RADIUS_MM as PUMA_RADIUS_MM
    from zrp.paper.scenario import CircleSetup as CircleSetup
    from zrp.paper.scenario import circle_joint_path as circle_joint_path
    from zrp.paper.scenario import is_paper_model as is_paper_model
    from zrp.paper.scenario import paper_start as paper_start
    from zrp.paper.scenario import puma_circle as puma_circle
    from zrp.paper.scenario import puma_circle_ik as puma_circle_ik
    from zrp.paper.scenes import PAPER_LEVELS as PAPER_LEVELS
    from zrp.paper.scenes import Scene as Scene
    from zrp.paper.scenes import SceneSegment as SceneSegment
    from zrp.paper.scenes import paper_magnification as paper_magnification
    from zrp.paper.scenes import paper_video_file_name as paper_video_file_name
    from zrp.paper.scenes import paper_video_scene as paper_video_scene
    from zrp.paper.scenes import perturbed_puma as perturbed_puma
    from zrp.paper.scenes import teaching_sweep_scene as teaching_sweep_scene

__all__ = [
    "CELL_STATUSES",
    "DEFAULT_PLACEMENT",
    "JE_PARAMS",
    "LE_PARAMS",
    "LIKELY_TYPOS",
    "PAPER_LEVELS",
    "PUBLISHED_ROWS",
    "PUBLISHED_TABLE2",
    "PUBLISHED_TABLE2_ZERO",
    "PUBLISHED_TABLE3",
    "PUBLISHED_TABLE3_ZERO",
    "PUMA_DURATION_S",
    "PUMA_Q0_DEG",
    "PUMA_RADIUS_MM",
    "RECOVERED",
    "Cell",
    "CellFit",
    "CirclePlacement",
    "CircleSetup",
    "PaperExample",
    "RecoveryResult",
    "Scene",
    "SceneSegment",
    "check_claims",
    "circle_joint_path",
    "compare_with_published",
    "comparison_csv",
    "comparison_markdown",
    "default_parameters",
    "fit_cells",
    "half_ulp",
    "implied_joint_angles",
    "is_paper_model",
    "kind_columns",
    "le3_readings",
    "local_pinning",
    "output_names",
    "paper_magnification",
    "paper_start",
    "paper_summary",
    "paper_video_file_name",
    "paper_video_scene",
    "perturbed_puma",
    "placement_path",
    "puma_circle",
    "puma_circle_ik",
    "recover_circle",
    "run_paper_example",
    "table_value",
    "teaching_sweep_scene",
    "write_index",
    "write_paper_outputs",
]
