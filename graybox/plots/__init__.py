"""Pictures: functions that take graybox values and return matplotlib Figures (no pyplot state).

The figures are built without pyplot, so nothing global changes and scripts need no backend.
Save one with ``fig.savefig("name.png")``; in Jupyter, run ``%matplotlib inline`` once and end a
cell with ``fig`` (or call ``IPython.display.display(fig)``) to see it.
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "_data": ("plot_record", "plot_static_curve"),
    "_models": ("plot_free_run",),
    "_pareto": ("plot_pareto",),
    "_surfaces": ("plot_surface_contours", "plot_surface_slices"),
    "_control": ("plot_local_models", "plot_operating_curve"),
    "_trust": ("plot_decision_bootstrap", "plot_residual_tests", "plot_simulation_band",
               "plot_static_band"),
})
