"""World benchmark: planning on a 20 m x 20 m map at 5 cm, and a map update from one scan.

Run: PYTHONPATH=src python bench/bench_world.py   (writes the `world` section of RESULTS.md)
"""

from __future__ import annotations

import random
import statistics
import time

from results import write_section
from shadowhound.robot.sim.scene import World, WorldObject
from shadowhound.robot.sim.sensors import cast_scan, scene_grid
from shadowhound.state import Pose2D
from shadowhound.world import OCCUPIED, OccupancyGrid, apply_scan, inflate, plan_path


def _cluttered(seed: int) -> OccupancyGrid:
    rng = random.Random(seed)
    objects = tuple(
        WorldObject(f"o{i}", rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(0.2, 0.6))
        for i in range(40)
    )
    grid = scene_grid(World(objects=objects, bounds=(-9.9, 9.9, -9.9, 9.9)))
    grid.fill_rect(-2.0, -1.8, -6.0, 9.9, OCCUPIED)  # a long wall to walk round
    return grid


def _rooms(seed: int) -> OccupancyGrid:
    # Twelve walls across the map, each with one 1.2 m doorway: the path zig-zags through all.
    rng = random.Random(seed)
    grid = scene_grid(World(objects=(), bounds=(-9.9, 9.9, -9.9, 9.9)))
    for i in range(12):
        x = -8 + i * 1.4
        gap = rng.uniform(-8, 7)
        grid.fill_rect(x, x + 0.1, -9.9, gap, OCCUPIED)
        grid.fill_rect(x, x + 0.1, gap + 1.2, 9.9, OCCUPIED)
    return grid


def main() -> None:
    plans: dict[str, list[float]] = {"cluttered": [], "rooms": []}
    infl: list[float] = []
    scans: list[float] = []
    for seed in range(10):
        for kind, make in (("cluttered", _cluttered), ("rooms", _rooms)):
            grid = make(seed)
            t = time.perf_counter()
            inflated = inflate(grid, 0.35)
            infl.append(time.perf_counter() - t)
            for start, goal in (((-9, -9), (9, 9)), ((-9, 9), (9, -9)), ((-9, 0.0), (9, 0.0))):
                if not (inflated.is_free_at(*start) and inflated.is_free_at(*goal)):
                    continue
                t = time.perf_counter()
                plan_path(inflated, start, goal)
                plans[kind].append(time.perf_counter() - t)
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
        "20 m x 20 m maps at 5 cm (400 x 400 cells), robot radius 0.35 m, pure Python "
        "(jump point search + shortcuts); measured on a 2-core machine shared with other jobs "
        "(loaded), so figures are pessimistic.\n\n"
        "| measure | median | target |\n|---|---|---|\n"
        f"| plan corner to corner, 40 cylinders and a long wall ({len(plans['cluttered'])} "
        f"plans) | {ms(plans['cluttered']):.1f} ms | < 50 ms |\n"
        f"| plan corner to corner through 12 walls with one doorway each "
        f"({len(plans['rooms'])} plans) | {ms(plans['rooms']):.1f} ms | < 50 ms |\n"
        f"| inflate the map by 0.35 m | {ms(infl):.1f} ms | - |\n"
        f"| update the map from one 360-beam scan | {ms(scans):.2f} ms | < 5 ms |\n"
        "<!-- world:end -->\n"
    )
    print(section)
    write_section("world", section)


if __name__ == "__main__":
    main()
