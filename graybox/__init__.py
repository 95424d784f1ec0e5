"""graybox: black- and gray-box identification of nonlinear dynamic systems.

Polynomial NARMAX models, structure selection, static analysis and gray-box estimation
with static-curve information, after Barbosa, Aguirre, Martinez & Braga (IEEE TCST 2011).

The implementation lives in private modules (``graybox._els`` …); every public name is
exported here, and from the public subpackages :mod:`graybox.datasets`, :mod:`graybox.plots`,
:mod:`graybox.experiments` and :mod:`graybox.reproduce`.
"""

from ._api import *  # noqa: F401,F403  (the core's public names)
from ._api import __version__
from . import plots
from . import experiments
from .experiments import GrayboxSelection, load_results, select_graybox

__all__ = [
    "Candidates", "Structure", "Term", "parse_term", "parse_structure",
    "Record", "StaticPoints", "Dataset", "StaticRangeWarning",
    "regressor_matrix", "stacked_regressors", "DaskRecord",
    "Model", "predict", "simulate", "simulate_many", "DivergenceError",
    "cluster_map", "equilibria", "static_curve", "static_gain", "Equilibrium",
    "evaluate", "evaluate_thetas", "j1", "js", "jsf", "mse", "rrse", "fit_percent",
    "frols", "Selection", "CandidateWarning", "information_criterion", "semp", "SEMPResult",
    "els", "ELSResult", "ELSConvergenceWarning", "noise_terms",
    "StaticCurve", "StaticSurface",
    "CurveEquality", "PassesThrough", "StaticBand", "GainBounds", "ClusterBounds", "UserConstraint",
    "InfeasibleError",
    "cls", "pe_pareto", "pe_thetas", "static_matrices", "qr_static_error", "PE_LAMBDAS",
    "ParetoSet", "nondominated_mask",
    "decide_dsf", "decide_min_correlation", "Decision",
    "se_pareto", "GAOptions", "SE_LAMBDAS", "se_dsf", "DSFResult",
    "neural_narx", "NeuralModel", "NeuralFit",
    "residual_tests", "ResidualTests", "CorrelationTest", "one_step_residuals",
    "ls_uncertainty", "cls_uncertainty", "pe_uncertainty", "se_uncertainty", "ParameterUncertainty",
    "UncertaintyWarning", "static_curve_band", "StaticCurveBand",
    "bootstrap_decision", "DecisionBootstrap", "BootstrapJob", "block_resample",
    "save", "load", "to_json", "from_json", "read_header", "GrayboxFileError", "FORMAT_VERSION",
    "datasets", "plots", "reference", "experiments",
    "load_pumping", "load_pumping_miso", "load_buck", "load_record_csv", "load_static_csv", "load_results", "select_graybox", "GrayboxSelection",
    "__version__",
]
# several inputs (issue 15): the static surface
__all__ += ["static_surface", "static_surface_gain", "surface_equilibria", "surface_cluster_map", "SurfaceClusterMap"]
