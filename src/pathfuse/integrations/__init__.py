"""Bridges to simulators that pathfuse did not write.

* :mod:`pathfuse.integrations.irsim` - drive a robot of an IR-SIM environment
  (PyPI ``ir-sim``, the extra ``pathfuse[irsim]``) with any online planner of
  pathfuse's registry: :class:`~pathfuse.integrations.irsim.IrsimController`.

Each module imports its simulator only when it is used, so ``import pathfuse``
never needs one.
"""
