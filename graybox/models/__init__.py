"""Models: the polynomial NARMAX model as an immutable value, and its figures of merit."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_model": ("Model",),
    "_evaluate": ("evaluate", "evaluate_thetas", "fit_percent", "j1", "js", "jsf", "mse", "rrse"),
})
