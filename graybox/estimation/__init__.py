"""Estimation: ELS, CLS and PE, SE (GA and gradient), output error, D_SF, Pareto sets and decisions, the neural baseline."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_pareto": ("ParetoSet", "nondominated_mask"),
    "_decisions": ("Decision", "decide_dsf", "decide_min_correlation"),
    "_extended_least_squares": ("ELSConvergenceWarning", "ELSResult", "els"),
    "_neural": ("NeuralFit", "NeuralModel", "neural_narx"),
    "_prediction_error": ("PE_LAMBDAS", "CLSResult", "cls", "pe_pareto", "pe_thetas"),
    "_local_models": ("SlowModeWarning",),
    "_simulation_error": ("SE_LAMBDAS", "GAOptions", "se_pareto"),
    "_output_error": ("OEResult", "output_error"),
    "_epsilon_constraint": ("DSFResult", "se_dsf"),
})
