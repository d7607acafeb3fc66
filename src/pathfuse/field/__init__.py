"""Artificial potential fields: forces (eq. 3-6) and the numba stepping kernel.

* :mod:`pathfuse.field.forces` -- the potentials and forces of the paper, as
  vectorised NumPy functions and scalar numba kernels.
* :mod:`pathfuse.field.stepper` -- the numba kernel: grid repulsion from a
  local window, the resultant forces of APF and of the fusion planner, the
  exact segment-clear test, the safe step, and the batch stepping loops.
* :mod:`pathfuse.field.driver` -- map-dependent defaults, parameter checks and
  the chunked driver that turns a batch loop into a status.

>>> from pathfuse.field import attractive_force
>>> attractive_force([0.0, 0.0], [1.0, 2.0], k_att=40.0).tolist()
[40.0, 80.0]
"""

from pathfuse.field.forces import (
    D_MIN_M,
    K_ATT,
    K_REP,
    RHO0_M,
    attractive_force,
    attractive_potential,
    repulsive_force,
    repulsive_potential,
    total_force,
)
from pathfuse.field.stepper import (
    apf_force,
    fusion_force,
    grid_repulsion,
    safe_step,
    segment_is_clear,
)

__all__ = [
    "K_ATT",
    "K_REP",
    "RHO0_M",
    "D_MIN_M",
    "attractive_potential",
    "attractive_force",
    "repulsive_potential",
    "repulsive_force",
    "total_force",
    "grid_repulsion",
    "apf_force",
    "fusion_force",
    "segment_is_clear",
    "safe_step",
]
