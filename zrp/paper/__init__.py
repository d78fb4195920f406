"""The paper's numerical example as a scenario: the Table 1 PUMA drawing a 125 mm circle
(:mod:`.scenario`), its perturbation study, the comparison with the published Tables 2-3 and
Figures 2-7 (:mod:`.example`).
"""

from zrp.paper.example import PUBLISHED_ROWS as PUBLISHED_ROWS
from zrp.paper.example import PUBLISHED_TABLE2 as PUBLISHED_TABLE2
from zrp.paper.example import PUBLISHED_TABLE2_ZERO as PUBLISHED_TABLE2_ZERO
from zrp.paper.example import PUBLISHED_TABLE3 as PUBLISHED_TABLE3
from zrp.paper.example import PUBLISHED_TABLE3_ZERO as PUBLISHED_TABLE3_ZERO
from zrp.paper.example import Cell as Cell
from zrp.paper.example import PaperExample as PaperExample
from zrp.paper.example import compare_with_published as compare_with_published
from zrp.paper.example import implied_joint_angles as implied_joint_angles
from zrp.paper.example import run_paper_example as run_paper_example
from zrp.paper.example import write_paper_outputs as write_paper_outputs
from zrp.paper.scenario import PUMA_Q0_DEG as PUMA_Q0_DEG
from zrp.paper.scenario import CircleSetup as CircleSetup
from zrp.paper.scenario import puma_circle as puma_circle
from zrp.paper.scenario import puma_circle_ik as puma_circle_ik

__all__ = [
    "PUBLISHED_ROWS",
    "PUBLISHED_TABLE2",
    "PUBLISHED_TABLE2_ZERO",
    "PUBLISHED_TABLE3",
    "PUBLISHED_TABLE3_ZERO",
    "PUMA_Q0_DEG",
    "Cell",
    "CircleSetup",
    "PaperExample",
    "compare_with_published",
    "implied_joint_angles",
    "puma_circle",
    "puma_circle_ik",
    "run_paper_example",
    "write_paper_outputs",
]
