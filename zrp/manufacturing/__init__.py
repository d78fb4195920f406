"""Manufacturing errors: perturbed link vectors and joint axes (eqs 8-12, :mod:`.perturb`),
pose deviations along a trajectory (eqs 15-17, :mod:`.deviation`), the parameter vector and its
identification Jacobian (re-exported from :mod:`zrp.kinematics.identification`), one-at-a-time
studies (:mod:`.study`), and the
tolerance analysis: tolerances and random draws (:mod:`.tolerance`), the nonlinear Monte Carlo
(:mod:`.population`; reduced on the workers for any size: :mod:`.reduction`), the first-order
budget (:mod:`.budget`), allocation (:mod:`.allocation`) and its figure (:mod:`.plots`). See
README.md in this folder.
"""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "ParameterSpace": "zrp.kinematics.identification",
    "apply_parameters": "zrp.kinematics.identification",
    "axis_tangents": "zrp.kinematics.identification",
    "parameter_jacobian": "zrp.kinematics.identification",
    "parameter_names": "zrp.kinematics.identification",
    "parameter_space": "zrp.kinematics.identification",
    "perturbed_arrays": "zrp.kinematics.identification",
    "pose_error": "zrp.kinematics.identification",
    "tilt_axes": "zrp.kinematics.identification",
    "Allocation": "zrp.manufacturing.allocation",
    "allocate_tolerances": "zrp.manufacturing.allocation",
    "Contribution": "zrp.manufacturing.budget",
    "contributions": "zrp.manufacturing.budget",
    "tolerance_report": "zrp.manufacturing.budget",
    "worst_case_bound": "zrp.manufacturing.budget",
    "ChunkResult": "zrp.manufacturing.chunks",
    "ChunkTask": "zrp.manufacturing.chunks",
    "chunk_rng": "zrp.manufacturing.chunks",
    "run_chunk": "zrp.manufacturing.chunks",
    "Deviation": "zrp.manufacturing.deviation",
    "check_times": "zrp.manufacturing.deviation",
    "delta_r_eq15": "zrp.manufacturing.deviation",
    "delta_r_literal": "zrp.manufacturing.deviation",
    "pose_deviation": "zrp.manufacturing.deviation",
    "trajectory_deviation": "zrp.manufacturing.deviation",
    "Histogram": "zrp.manufacturing.histogram",
    "PAPER_SIGN_ZERO": "zrp.manufacturing.perturb",
    "Perturbation": "zrp.manufacturing.perturb",
    "SignZero": "zrp.manufacturing.perturb",
    "check_xi_percent": "zrp.manufacturing.perturb",
    "parameter_label": "zrp.manufacturing.perturb",
    "parse_parameter": "zrp.manufacturing.perturb",
    "perturb_axis": "zrp.manufacturing.perturb",
    "perturb_components": "zrp.manufacturing.perturb",
    "perturbation_names": "zrp.manufacturing.perturb",
    "histogram_png": "zrp.manufacturing.plots",
    "MonteCarloResult": "zrp.manufacturing.population",
    "chunk_tasks": "zrp.manufacturing.population",
    "first_order_max": "zrp.manufacturing.population",
    "gather_chunks": "zrp.manufacturing.population",
    "monte_carlo": "zrp.manufacturing.population",
    "MonteCarloSummary": "zrp.manufacturing.reduction",
    "monte_carlo_summary": "zrp.manufacturing.reduction",
    "PAPER_PARAMETERS": "zrp.manufacturing.study",
    "PAPER_XI": "zrp.manufacturing.study",
    "JointPath": "zrp.manufacturing.study",
    "Linearity": "zrp.manufacturing.study",
    "StudyResult": "zrp.manufacturing.study",
    "fit_linearity": "zrp.manufacturing.study",
    "load_joint_csv": "zrp.manufacturing.study",
    "one_at_a_time": "zrp.manufacturing.study",
    "DISTRIBUTIONS": "zrp.manufacturing.tolerance",
    "Tolerances": "zrp.manufacturing.tolerance",
    "draw_parameters": "zrp.manufacturing.tolerance",
    "percentile_ci": "zrp.manufacturing.tolerance",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.kinematics.identification import ParameterSpace as ParameterSpace
    from zrp.kinematics.identification import apply_parameters as apply_parameters
    from zrp.kinematics.identification import axis_tangents as axis_tangents
    from zrp.kinematics.identification import parameter_jacobian as parameter_jacobian
    from zrp.kinematics.identification import parameter_names as parameter_names
    from zrp.kinematics.identification import parameter_space as parameter_space
    from zrp.kinematics.identification import perturbed_arrays as perturbed_arrays
    from zrp.kinematics.identification import pose_error as pose_error
    from zrp.kinematics.identification import tilt_axes as tilt_axes
    from zrp.manufacturing.allocation import Allocation as Allocation
    from zrp.manufacturing.allocation import allocate_tolerances as allocate_tolerances
    from zrp.manufacturing.budget import Contribution as Contribution
    from zrp.manufacturing.budget import contributions as contributions
    from zrp.manufacturing.budget import tolerance_report as tolerance_report
    from zrp.manufacturing.budget import worst_case_bound as worst_case_bound
    from zrp.manufacturing.chunks import ChunkResult as ChunkResult
    from zrp.manufacturing.chunks import ChunkTask as ChunkTask
    from zrp.manufacturing.chunks import chunk_rng as chunk_rng
    from zrp.manufacturing.chunks import run_chunk as run_chunk
    from zrp.manufacturing.deviation import Deviation as Deviation
    from zrp.manufacturing.deviation import check_times as check_times
    from zrp.manufacturing.deviation import delta_r_eq15 as delta_r_eq15
    from zrp.manufacturing.deviation import delta_r_literal as delta_r_literal
    from zrp.manufacturing.deviation import pose_deviation as pose_deviation
    from zrp.manufacturing.deviation import trajectory_deviation as trajectory_deviation
    from zrp.manufacturing.histogram import Histogram as Histogram
    from zrp.manufacturing.perturb import PAPER_SIGN_ZERO as PAPER_SIGN_ZERO
    from zrp.manufacturing.perturb import Perturbation as Perturbation
    from zrp.manufacturing.perturb import SignZero as SignZero
    from zrp.manufacturing.perturb import check_xi_percent as check_xi_percent
    from zrp.manufacturing.perturb import parameter_label as parameter_label
    from zrp.manufacturing.perturb import parse_parameter as parse_parameter
    from zrp.manufacturing.perturb import perturb_axis as perturb_axis
    from zrp.manufacturing.perturb import perturb_components as perturb_components
    from zrp.manufacturing.perturb import perturbation_names as perturbation_names
    from zrp.manufacturing.plots import histogram_png as histogram_png
    from zrp.manufacturing.population import MonteCarloResult as MonteCarloResult
    from zrp.manufacturing.population import chunk_tasks as chunk_tasks
    from zrp.manufacturing.population import first_order_max as first_order_max
    from zrp.manufacturing.population import gather_chunks as gather_chunks
    from zrp.manufacturing.population import monte_carlo as monte_carlo
    from zrp.manufacturing.reduction import MonteCarloSummary as MonteCarloSummary
    from zrp.manufacturing.reduction import monte_carlo_summary as monte_carlo_summary
    from zrp.manufacturing.study import PAPER_PARAMETERS as PAPER_PARAMETERS
    from zrp.manufacturing.study import PAPER_XI as PAPER_XI
    from zrp.manufacturing.study import JointPath as JointPath
    from zrp.manufacturing.study import Linearity as Linearity
    from zrp.manufacturing.study import StudyResult as StudyResult
    from zrp.manufacturing.study import fit_linearity as fit_linearity
    from zrp.manufacturing.study import load_joint_csv as load_joint_csv
    from zrp.manufacturing.study import one_at_a_time as one_at_a_time
    from zrp.manufacturing.tolerance import DISTRIBUTIONS as DISTRIBUTIONS
    from zrp.manufacturing.tolerance import Tolerances as Tolerances
    from zrp.manufacturing.tolerance import draw_parameters as draw_parameters
    from zrp.manufacturing.tolerance import percentile_ci as percentile_ci

__all__ = [
    "DISTRIBUTIONS",
    "PAPER_PARAMETERS",
    "PAPER_SIGN_ZERO",
    "PAPER_XI",
    "Allocation",
    "ChunkResult",
    "ChunkTask",
    "Contribution",
    "Deviation",
    "Histogram",
    "JointPath",
    "Linearity",
    "MonteCarloResult",
    "MonteCarloSummary",
    "ParameterSpace",
    "Perturbation",
    "SignZero",
    "StudyResult",
    "Tolerances",
    "allocate_tolerances",
    "apply_parameters",
    "axis_tangents",
    "check_times",
    "check_xi_percent",
    "chunk_rng",
    "chunk_tasks",
    "contributions",
    "delta_r_eq15",
    "delta_r_literal",
    "draw_parameters",
    "first_order_max",
    "fit_linearity",
    "gather_chunks",
    "histogram_png",
    "load_joint_csv",
    "monte_carlo",
    "monte_carlo_summary",
    "one_at_a_time",
    "parameter_jacobian",
    "parameter_label",
    "parameter_names",
    "parameter_space",
    "parse_parameter",
    "percentile_ci",
    "perturb_axis",
    "perturb_components",
    "perturbation_names",
    "perturbed_arrays",
    "pose_deviation",
    "pose_error",
    "run_chunk",
    "tilt_axes",
    "tolerance_report",
    "trajectory_deviation",
    "worst_case_bound",
]
