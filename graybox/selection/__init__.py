"""Structure selection: FROLS (error reduction ratio) and SEMP (simulation error with pruning)."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_forward_regression": ("CandidateWarning", "Selection", "frols", "information_criterion"),
    "_simulation_error_pruning": ("SEMPResult", "semp"),
})
