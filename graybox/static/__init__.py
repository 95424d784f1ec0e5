"""Static analysis: clusters, equilibria and their stability, static curves, surfaces and gains; constraints."""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_analysis": ("Equilibrium", "cluster_map", "equilibria", "static_curve", "static_gain"),
    "_surface_analysis": ("SurfaceClusterMap", "static_surface", "static_surface_gain", "surface_cluster_map",
                          "surface_equilibria"),
    "_curves": ("StaticCurve",),
    "_surfaces": ("StaticSurface",),
    "_constraints": ("ClusterBounds", "CurveEquality", "GainBounds", "InfeasibleError", "PassesThrough", "StaticBand",
                     "UserConstraint"),
})
