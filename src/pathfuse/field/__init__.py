"""Artificial potential fields: the paper's forces and the numba kernels that step with them.

* :mod:`pathfuse.field.forces` - the potentials and forces of eq. 3-6, as
  vectorised NumPy functions and scalar numba kernels.
* :mod:`pathfuse.field.repulsion` - repulsion on a grid (plain and Ge-Cui),
  the resultants of APF and of Algorithm 2, and the moving discs' repulsion.
* :mod:`pathfuse.field.motion` - the collision-free safe step.
* :mod:`pathfuse.field.pathing` - progress along a path and the rejoin point
  of an escape.
* :mod:`pathfuse.field.kernels` - the stepping loops of the controllers,
  shared by :func:`pathfuse.plan` and :func:`pathfuse.simulate`.

>>> from pathfuse.field.forces import attractive_force
>>> attractive_force([0.0, 0.0], [1.0, 2.0], k_att=40.0).tolist()
[40.0, 80.0]
"""
