"""How long reading a Gazebo world takes: ``load_map`` on every shipped BARN world.

For each resolution, every world of ``--barn`` is read with
:func:`pathfuse.io.gazebo.read_gazebo_world` (parse, poses, exact rasterisation,
BARN's bounds); the script prints the median wall and CPU time per world, the
split between parsing (:func:`world_footprints`) and the whole read, and the load
average.  There is no peer to compare with: the tools a user would otherwise pick
(a Gazebo plugin that ray-casts the running world into a map) need Gazebo itself.

Usage: ``python benchmarks/bench_gazebo.py [--barn ../shared/data/barn]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from pathfuse.io.gazebo import read_gazebo_world, world_footprints
from pathfuse.studies.barn import BARN_BOUNDS, find_worlds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--barn", default=str(Path(__file__).parents[1] / ".." / ".." / "shared"
                                           / "data" / "barn"))
    a = ap.parse_args()
    worlds = find_worlds(a.barn)
    print(f"{len(worlds)} BARN worlds, {platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.2f}")
    parse = []
    for w in worlds:
        c = time.process_time()
        world_footprints(w.world)
        parse.append(time.process_time() - c)
    print(f"parse only: median {1e3 * np.median(parse):.1f} ms CPU per world")
    for res in (0.05, 0.1, 0.15):
        wall, cpu, cells = [], [], 0
        for w in worlds:
            t, c = time.perf_counter(), time.process_time()
            g = read_gazebo_world(w.world, res, bounds=BARN_BOUNDS)
            wall.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
            cells = g.occupied.size
        print(f"read_gazebo_world at {res:g} m ({cells} cells): median "
              f"{1e3 * np.median(wall):.1f} ms wall, {1e3 * np.median(cpu):.1f} ms CPU per world")
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
