"""Diagnostics: residual correlation tests, parameter, static-curve and free-run uncertainty, bootstrap of a decision."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_residuals": ("CorrelationTest", "ResidualTests", "one_step_residuals", "residual_tests"),
    "_uncertainty": ("ParameterUncertainty", "StaticCurveBand", "UncertaintyWarning", "cls_uncertainty",
                     "ls_uncertainty", "pe_uncertainty", "se_uncertainty", "static_curve_band",
                     "StaticSurfaceBand", "static_surface_band"),
    "_simulation_band": ("SimulationBand", "simulation_band"),
    "_bootstrap": ("DecisionBootstrap", "bootstrap_decision"),
})
