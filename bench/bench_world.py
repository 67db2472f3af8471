"""World benchmark: planning on a 20 m x 20 m map at 5 cm, and a map update from one scan.

Run: PYTHONPATH=src python bench/bench_world.py   (writes the `world` section of RESULTS.md)
"""

from __future__ import annotations

import random
import statistics
import time

from results import write_section
from shadowhound.robot.scene import World, WorldObject
from shadowhound.robot.sensors import cast_scan, scene_grid
from shadowhound.state import Pose2D
from shadowhound.world import OCCUPIED, OccupancyGrid, apply_scan, inflate, plan_path


def _map(seed: int) -> OccupancyGrid:
    rng = random.Random(seed)
    objects = tuple(WorldObject(f"o{i}", rng.uniform(-8, 8), rng.uniform(-8, 8),
                                rng.uniform(0.2, 0.6)) for i in range(40))
    grid = scene_grid(World(objects=objects, bounds=(-9.9, 9.9, -9.9, 9.9)))
    grid.fill_rect(-2.0, -1.8, -6.0, 9.9, OCCUPIED)  # a long wall to walk round
    return grid


def main() -> None:
    plans, infl, scans = [], [], []
    for seed in range(10):
        grid = _map(seed)
        t = time.perf_counter()
        inflated = inflate(grid, 0.35)
        infl.append(time.perf_counter() - t)
        for start, goal in (((-9, -9), (9, 9)), ((-9, 9), (9, -9)), ((-9, 0.0), (9, 0.0))):
            if not (inflated.is_free_at(*start) and inflated.is_free_at(*goal)):
                continue
            t = time.perf_counter()
            plan_path(inflated, start, goal)
            plans.append(time.perf_counter() - t)
    world = World(objects=(WorldObject("ball", 3.0, 0.0, 0.2),), bounds=(-6, 6, -6, 6))
    scan = cast_scan(world, Pose2D(0.0, 0.0, 0.0))
    for _ in range(30):
        grid = OccupancyGrid.empty(-10, 10, -10, 10)
        t = time.perf_counter()
        apply_scan(grid, scan)
        scans.append(time.perf_counter() - t)
    ms = lambda xs: statistics.median(xs) * 1000  # noqa: E731
    section = (
        "<!-- world:start -->\n## World (issue 15, phase 1)\n\n"
        "20 m x 20 m map at 5 cm (400 x 400), 40 random cylinders and a wall; machine shared "
        "with other jobs (loaded), so figures are pessimistic.\n\n"
        "| measure | median | target |\n|---|---|---|\n"
        f"| plan a path corner to corner ({len(plans)} plans) | {ms(plans):.1f} ms | < 50 ms |\n"
        f"| inflate the map by 0.35 m | {ms(infl):.1f} ms | - |\n"
        f"| update the map from one 360-beam scan | {ms(scans):.2f} ms | < 5 ms |\n"
        "<!-- world:end -->\n"
    )
    print(section)
    write_section("world", section)


if __name__ == "__main__":
    main()
