"""graybox: black- and gray-box identification of nonlinear dynamic systems.

Polynomial NARMAX models, structure selection, static analysis and gray-box estimation
with static-curve information, after Barbosa, Aguirre, Martinez & Braga (IEEE TCST 2011).

The implementation lives in private modules (``graybox._els`` …); every public name is
exported here, and from the public subpackages :mod:`graybox.datasets`, :mod:`graybox.plots`,
:mod:`graybox.experiments` and :mod:`graybox.reproduce`.
"""

from importlib.metadata import PackageNotFoundError, version as _version

from ._terms import Candidates, Structure, Term, parse_structure, parse_term
from ._records import Dataset, Record, StaticPoints, StaticRangeWarning
from ._regressors import regressor_matrix, stacked_regressors
from ._gram import DaskRecord
from ._simulation import DivergenceError, predict, simulate, simulate_many
from ._model import Model
from ._static import Equilibrium, cluster_map, equilibria, static_curve, static_gain
from ._static_surface import SurfaceClusterMap, static_surface, static_surface_gain, surface_cluster_map, surface_equilibria
from ._evaluate import evaluate, evaluate_thetas, fit_percent, j1, js, jsf, mse, rrse
from ._selection import CandidateWarning, Selection, frols, information_criterion
from ._semp import SEMPResult, semp
from ._els import ELSConvergenceWarning, ELSResult, els, noise_terms
from ._curves import StaticCurve
from ._surfaces import StaticSurface
from ._constraints import (
    ClusterBounds, CurveEquality, GainBounds, InfeasibleError, PassesThrough, StaticBand, UserConstraint,
)
from ._convex import PE_LAMBDAS, cls, pe_pareto, pe_thetas, qr_static_error, static_matrices
from ._pareto import ParetoSet, nondominated_mask
from ._se import SE_LAMBDAS, GAOptions, se_pareto
from ._se_dsf import DSFResult, se_dsf
from ._decide import Decision, decide_dsf, decide_min_correlation
from ._neural import NeuralFit, NeuralModel, neural_narx
from ._residuals import CorrelationTest, ResidualTests, one_step_residuals, residual_tests
from ._uncertainty import (
    ParameterUncertainty, StaticCurveBand, UncertaintyWarning, cls_uncertainty, ls_uncertainty, pe_uncertainty,
    se_uncertainty, static_curve_band,
)
from ._bootstrap import BootstrapJob, DecisionBootstrap, block_resample, bootstrap_decision
from ._io import FORMAT_VERSION, GrayboxFileError, from_json, load, read_header, save, to_json
from . import datasets, plots, reference
from .datasets import load_buck, load_pumping, load_pumping_miso, load_record_csv, load_static_csv
from . import experiments
from .experiments import GrayboxSelection, load_results, select_graybox

try:
    __version__ = _version("graybox")
except PackageNotFoundError:  # pragma: no cover - running from a source tree that was never installed
    __version__ = "0+unknown"

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
