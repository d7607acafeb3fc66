"""Figures and animations.  The only package of pathfuse that imports matplotlib."""

from pathfuse.viz.figures import draw_map, plot_plan

__all__ = ["draw_map", "plot_plan"]
