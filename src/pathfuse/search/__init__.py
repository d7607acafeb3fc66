"""Graph search on occupancy grids: exact 8-connected A* (:mod:`pathfuse.search.astar`)."""

from pathfuse.search.astar import HEURISTICS, AStarSearcher, SearchResult, get_searcher, warmup

__all__ = ["AStarSearcher", "SearchResult", "get_searcher", "warmup", "HEURISTICS"]
