"""Planners: every one registered in :mod:`pathfuse.planners.registry`."""

from pathfuse.planners.registry import REGISTRY, PlannerSpec, get_planner, planner_names

__all__ = ["REGISTRY", "PlannerSpec", "get_planner", "planner_names"]
