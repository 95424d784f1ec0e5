"""Core: terms and structures, records, regressors, compiled free runs, Gram matrices, least squares."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_terms": ("Candidates", "Structure", "Term", "parse_structure", "parse_term", "transient_name"),
    "_records": ("Dataset", "Record", "StaticPoints", "StaticRangeWarning", "RecordOverlapWarning"),
    "_transient": ("transient_inputs",),
    "_regressors": ("regressor_matrix", "stacked_regressors"),
    "_gram": ("DaskRecord",),
    "_simulation": ("DivergenceError", "predict", "simulate", "simulate_many"),
})
