"""The layer order of the package: the one place it is written.

Bottom first. A unit is a subpackage (with its modules, themselves ordered bottom first) or a
top-level module. A module may import any module of an earlier unit, and, inside its own
subpackage, only the modules listed before it (the subpackage's ``__init__`` sits on top of its
own modules). ``tests/test_layers.py`` holds every import in the package to this order, imports
inside functions included, and checks the README's layout table against it.

This module imports nothing, so anything may read it.
"""

from __future__ import annotations

#: (unit, its modules bottom first, what it owns) — bottom first.
LAYERS: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("_layers", (), "this order"),
    ("_lazy", (), "the lazy re-export of public names (``import graybox`` loads no heavy dependency)"),
    ("core", ("_jit", "_version", "_renamed", "_reprs", "_validation", "_progress", "_terms", "_equation_text", "_records", "_transient", "_processes", "_files", "_regressors",
              "_simulation_kernels", "_gram", "_least_squares", "_simulation"),
     "terms and structures, records and data sets, argument checks, regressors, compiled free runs, "
     "Gram matrices and long records, scaled least squares"),
    ("static", ("_equilibrium_kernels", "_linearisation", "_analysis", "_surface_analysis", "_curves", "_surfaces", "_constraints",
                "_form_check"),
     "clusters, equilibria and their stability, static curves, surfaces and gains; static curves and "
     "surfaces fitted to points; static constraints as affine rows"),
    ("models", ("_model", "_coerce", "_evaluate"),
     "the polynomial NARMAX model as a value; J_1, J_S, J_SF and the other figures of merit"),
    ("selection", ("_stopping", "_subset_search", "_centring", "_forward_regression", "_simulation_error_pruning"),
     "structure selection: FROLS (ERR) and SEMP (simulation error with pruning)"),
    ("estimation", ("_pareto", "_decisions", "_extended_least_squares", "_neural", "_prediction_error",
                    "_local_models", "_simulation_error", "_output_error", "_epsilon_constraint"),
     "ELS, CLS and PE (cvxpy QPs and the closed form), SE (GA and gradient) with a stability margin, "
     "output error, D_SF solved directly, Pareto sets and decision makers, the neural baseline"),
    ("diagnostics", ("_residuals", "_uncertainty", "_simulation_band", "_bootstrap"),
     "residual correlation tests, parameter, static-curve and free-run uncertainty, bootstrap of a decision"),
    ("control", ("_local", "_systems"),
     "local linear models at operating points and along the static curve; the bridge to python-control "
     "(LTI local models, the whole model as a discrete nonlinear system)"),
    ("io", ("_json",), "save and load graybox values as JSON (never pickle)"),
    ("reference", (), "the paper's identified models (Tables II and III) and its comparison (Table I) as data"),
    ("datasets", ("_decimation", "_inputs", "pumping", "_pumping_miso", "_loaders", "_miso_loader"),
     "input design, decimation, the bundled plant simulators and their data, the buck converter, CSV loaders"),
    ("_api", (), "every public name below this line, as one namespace"),
    ("plots", ("_data", "_models", "_pareto", "_surfaces", "_trust", "_control"), "figures (matplotlib, no pyplot)"),
    ("experiments", ("_example", "_spec", "_cell", "_store", "_dask_worker", "_dask", "_executors", "_map", "_run", "_html",
                     "_report", "_select_checkpoint", "_select", "_selection_plot"),
     "grids of data × structures × variants × seeds on Dask or in-process, the SQLite store, reports, "
     "and ``select_graybox``"),
    ("reproduce", ("_paper_models", "_black_box", "_neural", "_table1"), "the paper's sections, Table I and figures"),
    ("_cli", (), "the ``graybox`` command"),
    ("__main__", (), "``python -m graybox``, the same command"),
    ("__init__", (), "the package's public names"),
)

#: Subpackages whose public names ``graybox`` re-exports, in layer order.
PUBLIC_SUBPACKAGES: tuple[str, ...] = ("core", "static", "models", "selection", "estimation", "diagnostics", "control",
                                       "io", "datasets")
