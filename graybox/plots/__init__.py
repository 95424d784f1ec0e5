"""Pictures: functions that take graybox values and return matplotlib Figures (no pyplot state).

The figures are built without pyplot, so nothing global changes and scripts need no backend.
Save one with ``fig.savefig("name.png")``; in Jupyter, run ``%matplotlib inline`` once and end a
cell with ``fig`` (or call ``IPython.display.display(fig)``) to see it.
"""

from ._data import plot_record, plot_static_curve
from ._models import plot_free_run
from ._pareto import plot_pareto
from ._surfaces import plot_surface_contours, plot_surface_slices
from ._trust import plot_decision_bootstrap, plot_residual_tests, plot_static_band

__all__ = ["plot_record", "plot_static_curve", "plot_free_run", "plot_pareto", "plot_residual_tests", "plot_static_band",
           "plot_decision_bootstrap", "plot_surface_slices", "plot_surface_contours"]
