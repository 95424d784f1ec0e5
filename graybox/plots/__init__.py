"""Pictures: functions that take graybox values and return matplotlib Figures (no pyplot state)."""

from .data import plot_record, plot_static_curve
from .models import plot_free_run
from .pareto import plot_pareto

__all__ = ["plot_record", "plot_static_curve", "plot_free_run", "plot_pareto"]
