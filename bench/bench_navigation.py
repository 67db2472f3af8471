"""Navigation benchmark: every case of tests/data/missions_navigation.yaml on the simulator,
with the offline planner: the path walked against the optimal 8-connected grid path, the robot
clock, re-plans and the wall-clock cost of the whole mission (planning and control). For an
object case the optimal path ends where the robot stopped (the standoff it chose); a case whose
object is out of view at the start includes its search.

Run: PYTHONPATH=src python bench/bench_navigation.py   (writes the `navigation` section)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from results import write_section
from shadowhound.config import ShadowHoundConfig
from shadowhound.evaluation import run_case

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from test_navigation_eval import (  # noqa: E402
    CASES,
    goals_of,
    in_view_at_start,
    optimal_grid_length,
    target_object,
)


def main() -> None:
    rows = []
    passed = 0
    for case in CASES:
        began = time.perf_counter()
        outcome = run_case(case, ShadowHoundConfig())
        wall = time.perf_counter() - began
        passed += outcome.passed
        a = outcome.actual
        kind = "-"
        if target_object(case) is not None:
            kind = "object in view" if in_view_at_start(case) else "object searched for"
        if case.expect.get("success"):
            end = (a["x"], a["y"]) if target_object(case) is not None else None
            optimal = optimal_grid_length(case, goals_of(case, end))
            ratio = f"{a['path_length'] / optimal:.3f}"
            length = f"{a['path_length']:.2f} m / {optimal:.2f} m"
        else:
            ratio, length = "-", "refused: " + outcome.response.split(": ", 2)[-1][:60]
        rows.append(
            f"| {case.mission} | {kind} | {'pass' if outcome.passed else 'FAIL'} | "
            f"{length} | "
            f"{ratio} | {a['seconds']:.1f} s | {a['replans']} | {wall * 1000:.0f} ms |"
        )
    section = "\n".join(
        [
            "<!-- navigation:start -->",
            "## Navigation cases (issue 15, phase 2a and objects)",
            "",
            f"`tests/data/missions_navigation.yaml` with the offline planner: "
            f"{passed}/{len(CASES)} passed. Walked = the simulator's true path; optimal = the "
            "shortest 8-connected path on the true scene's grid inflated by the body (0.35 m). "
            "Wall time includes planning (each nav.goto plans when checked, re-checked and run, "
            "and renders a camera frame "
            "after each move for sightings) on a shared machine (load average "
            f"{os.getloadavg()[0]:.0f} on {os.cpu_count()} cores). "
            "Object cases: the optimal path ends at the standoff the robot chose; a searched-for "
            "object's walk includes the search.",
            "",
            "| mission | kind | result | walked / optimal | ratio | robot time | re-plans | wall "
            "time |",
            "|---|---|---|---|---|---|---|---|",
            *rows,
            "<!-- navigation:end -->",
        ]
    )
    write_section("navigation", section)
    print(section)


if __name__ == "__main__":
    main()
