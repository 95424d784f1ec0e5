"""Pictures: functions that take graybox values and return matplotlib Figures (no pyplot state)."""

from .data import plot_record, plot_static_curve

__all__ = ["plot_record", "plot_static_curve"]
