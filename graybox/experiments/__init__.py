"""Experiments: grids of data sets × structures × variants × seeds, run anywhere, kept in SQLite.

A *grid* is declared in Python (:class:`Grid` of :class:`DataSpec`, :class:`StructureSpec`,
:class:`Variant`) or in a TOML file with the same content (``graybox grid init`` prints a
commented example). A *cell* is one (data, structure, variant, seed): the structure is made (or
taken), the estimator runs with its constraints and λ set, the decision maker picks a member,
and the shared evaluator scores the chosen model on the identification AND the validation
records. :func:`run_grid` runs the cells not yet in the store — in the driver, in local
processes or on a Dask cluster — and commits each row as it completes, so a killed run resumes
where it stopped, and a grid grown by a data set, structure, variant, seed or option runs only
its new cells. The store keeps every spec run on it (:func:`store_specs`). :func:`load_results`
reads a store as a DataFrame (the latest spec's cells, one spec's, or all); the report functions
turn it into a leaderboard whose empty rows say why, a heat map, figures and one HTML page;
:func:`grid_status` shows a run's progress from another process; :func:`compare_results` puts
stores side by side.

This package sits above the estimators and the decision makers; nothing in graybox below it
imports it.
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_cell": ("COLUMNS", "STATUSES", "run_cell"),
    "_example": ("EXAMPLE_SPEC",),
    "_executors": ("EXECUTORS",),
    "_report": ("RULES", "GridStatus", "grid_status", "heatmap_table", "leaderboard", "plot_fronts", "plot_heatmap", "plot_scatter", "write_report"),
    "_map": ("parallel_map",),
    "_run": ("GridRun", "run_grid"),
    "_select": ("BLACK_BOX_ESTIMATORS", "GRAY_BOX_ESTIMATORS", "GrayboxSelection", "SelectionWarning", "select_graybox"),
    "_selection_plot": ("plot_selection",),
    "_spec": ("BUNDLED", "CONSTRAINT_TYPES", "DECISION_RULES", "ESTIMATORS", "Cell", "DataSpec", "DecisionRule", "Grid",
              "SpecError", "SpecTypeError", "StructureSpec", "Variant"),
    "_store": ("StoreError", "compare_results", "load_results", "store_specs"),
})
