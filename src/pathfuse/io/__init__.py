"""Map and scenario input/output.

* :mod:`pathfuse.io.movingai` - MovingAI ``.map`` files; :mod:`pathfuse.io.scenario` -
  MovingAI ``.scen`` benchmark queries.
* :mod:`pathfuse.io.ros` - ROS ``map_server`` maps (YAML + PGM/PNG).
* :mod:`pathfuse.io.image` - plain images and ``.npy`` arrays.
* :mod:`pathfuse.io.inline` - small maps as text rows in YAML.
* :mod:`pathfuse.io.load` - :func:`load_map` and :func:`map_from_spec`, which
  pick the right reader.

Every reader returns a :class:`~pathfuse.grid.GridMap` whose row 0 is the
*bottom* of the map; formats stored top row first (MovingAI, images, ROS,
text rows) are flipped on reading.  ``.npy`` arrays are already in pathfuse
order and are not flipped.
"""

from pathfuse.io.image import read_image, read_npy
from pathfuse.io.inline import read_rows_yaml
from pathfuse.io.load import load_map, map_from_spec
from pathfuse.io.movingai import read_movingai, write_movingai
from pathfuse.io.ros import read_ros_map, write_ros_map
from pathfuse.io.scenario import ScenProblem, read_scen

__all__ = [
    "read_movingai",
    "write_movingai",
    "read_scen",
    "ScenProblem",
    "read_ros_map",
    "write_ros_map",
    "read_image",
    "read_npy",
    "read_rows_yaml",
    "load_map",
    "map_from_spec",
]
