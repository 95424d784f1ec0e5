"""Every public name of the core (everything below the experiment layer), in one namespace.

:mod:`graybox` re-exports it; the experiment layer reads the core through it
(``from .. import _api as gb``), so that nothing in :mod:`graybox.experiments` imports the
package that imports it.
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
from . import datasets, reference
from .datasets import load_buck, load_pumping, load_pumping_miso, load_record_csv, load_static_csv

try:
    __version__ = _version("graybox")
except PackageNotFoundError:  # pragma: no cover - running from a source tree that was never installed
    __version__ = "0+unknown"


__all__ = sorted(n for n in dir() if not n.startswith("_") and n not in ("PackageNotFoundError", "annotations"))
__all__ += ["__version__"]
