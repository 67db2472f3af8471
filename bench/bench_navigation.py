"""Navigation benchmark: every case of tests/data/missions_navigation.yaml on the simulator,
with the offline planner: the path walked against the optimal 8-connected grid path, the robot
clock, re-plans and the wall-clock cost of the whole mission (planning and control).

Run: PYTHONPATH=src python bench/bench_navigation.py   (writes the `navigation` section)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from results import write_section
from shadowhound.config import ShadowHoundConfig
from shadowhound.evaluation import run_case

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from test_navigation_eval import CASES, goals_of, optimal_grid_length  # noqa: E402


def main() -> None:
    rows = []
    passed = 0
    for case in CASES:
        began = time.perf_counter()
        outcome = run_case(case, ShadowHoundConfig())
        wall = time.perf_counter() - began
        passed += outcome.passed
        a = outcome.actual
        if case.expect.get("success"):
            optimal = optimal_grid_length(case, goals_of(case))
            ratio = f"{a['path_length'] / optimal:.3f}"
            length = f"{a['path_length']:.2f} m / {optimal:.2f} m"
        else:
            ratio, length = "-", "refused: " + outcome.response.split(": ", 2)[-1][:60]
        rows.append(f"| {case.mission} | {'pass' if outcome.passed else 'FAIL'} | {length} | "
                    f"{ratio} | {a['seconds']:.1f} s | {a['replans']} | {wall * 1000:.0f} ms |")
    section = "\n".join([
        "<!-- navigation:start -->",
        "## Navigation cases (issue 15, phase 2a)",
        "",
        f"`tests/data/missions_navigation.yaml` with the offline planner: {passed}/{len(CASES)} "
        "passed. Walked = the simulator's true path; optimal = the shortest 8-connected path on "
        "the true scene's grid inflated by the body (0.35 m). Wall time includes planning "
        "(each nav.goto plans when checked, re-checked and run) on a loaded 2-core machine.",
        "",
        "| mission | result | walked / optimal | ratio | robot time | re-plans | wall time |",
        "|---|---|---|---|---|---|---|",
        *rows,
        "<!-- navigation:end -->",
    ])
    write_section("navigation", section)
    print(section)


if __name__ == "__main__":
    main()
