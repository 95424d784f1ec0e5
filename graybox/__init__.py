"""graybox: black- and gray-box identification of nonlinear dynamic systems.

Polynomial NARMAX models, structure selection, static analysis and gray-box estimation
with static-curve information, after Barbosa, Aguirre, Martinez & Braga (IEEE TCST 2011).
"""

from .evaluate import evaluate, fit_percent, j1, js, jsf, mse, rrse
from .model import Model
from .records import Dataset, Record, StaticPoints
from .regressors import regressor_matrix, stacked_regressors
from .simulation import DivergenceError, predict, simulate, simulate_many
from .static import Equilibrium, cluster_map, equilibria, static_curve, static_gain
from .terms import Candidates, Structure, Term, parse_structure, parse_term
from .selection import CandidateWarning, Selection, frols, information_criterion
from .els import ELSConvergenceWarning, ElsInfo, els, noise_terms
from .curves import StaticCurve
from .constraints import (
    ClusterBounds, CurveEquality, GainBounds, InfeasibleError, PassesThrough, StaticBand, UserConstraint,
)
from .convex import cls, pe_pareto, pe_thetas, qr_static_error, static_matrices
from .pareto import ParetoSet, nondominated_mask
from .decide import decide_dsf
from .se import GAOptions, se_pareto
from .neural import NeuralModel, NeuralTrainInfo, neural_narx
from . import datasets, reference
from .datasets import load_buck, load_pumping, load_record_csv, load_static_csv

__version__ = "0.1.0"

__all__ = [
    "Candidates", "Structure", "Term", "parse_term", "parse_structure",
    "Record", "StaticPoints", "Dataset",
    "regressor_matrix", "stacked_regressors",
    "Model", "predict", "simulate", "simulate_many", "DivergenceError",
    "cluster_map", "equilibria", "static_curve", "static_gain", "Equilibrium",
    "evaluate", "j1", "js", "jsf", "mse", "rrse", "fit_percent",
    "frols", "Selection", "CandidateWarning", "information_criterion",
    "els", "ElsInfo", "ELSConvergenceWarning", "noise_terms",
    "StaticCurve",
    "CurveEquality", "PassesThrough", "StaticBand", "GainBounds", "ClusterBounds", "UserConstraint",
    "InfeasibleError",
    "cls", "pe_pareto", "pe_thetas", "static_matrices", "qr_static_error",
    "ParetoSet", "nondominated_mask", "decide_dsf",
    "se_pareto", "GAOptions",
    "neural_narx", "NeuralModel", "NeuralTrainInfo",
    "datasets", "load_pumping", "load_buck", "load_record_csv", "load_static_csv",
    "reference",
]
