"""The version of pathfuse (one place; ``pathfuse.__version__`` reads it)."""

__version__ = "0.1.0"
