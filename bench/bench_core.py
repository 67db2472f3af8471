"""Core benchmarks (issue: offline planning, dispatch overhead, CLI start-up).

Run:  .venv/bin/python bench/bench_core.py [--write]
--write replaces the "core" section of bench/RESULTS.md with the figures measured now.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import statistics
import subprocess
import sys
import time
import timeit
from pathlib import Path

from results import write_section
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, SkillCall, default_registry
from shadowhound.planning.rules import RulePlanner
from shadowhound.skills import NoArgs, Skill

FIVE_STEPS = (
    "stand up, walk forward 2 meters, turn left 90 degrees, "
    "then walk forward one and a half meters and sit down"
)


def bench_planning() -> dict[str, float]:
    planner = RulePlanner()
    plan = planner.plan(FIVE_STEPS)
    assert len(plan.steps) == 5, plan.steps
    runs = timeit.repeat(lambda: planner.plan(FIVE_STEPS), number=2000, repeat=7)
    per_call = [r / 2000 for r in runs]
    return {"median_us": statistics.median(per_call) * 1e6, "best_us": min(per_call) * 1e6}


def bench_dispatch(steps: int = 1000) -> dict[str, float]:
    """Per-step cost of the agent itself: validation, safety check, context, events, results.

    A no-op skill isolates the dispatch path; the simulated robot runs at time scale 0, so no
    simulated time is waited for.
    """
    registry = default_registry()
    registry.register(Skill("bench.noop", "does nothing", NoArgs, lambda ctx, a: "ok"))
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), registry=registry))
    agent.settings.agent.max_steps = steps
    calls = [SkillCall("bench.noop")] * steps
    agent.run_plan(calls[:10])  # warm up
    totals = []
    for _ in range(5):
        result = agent.run_plan(calls)
        assert result.success, result.response
        totals.append(result.timing.total_duration / steps)
    stand = [SkillCall("body.stand")] * 200  # a real skill whose robot work is a no-op
    stand_totals = []
    for _ in range(5):
        result = agent.run_plan(stand)
        stand_totals.append(result.timing.total_duration / len(stand))
    return {
        "noop_median_ms": statistics.median(totals) * 1e3,
        "stand_median_ms": statistics.median(stand_totals) * 1e3,
    }


def bench_cli(runs: int = 7) -> dict[str, float]:
    exe = shutil.which("shadowhound", path=str(Path(sys.executable).parent)) or "shadowhound"
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        proc = subprocess.run(
            [exe, "run", "--json", "--quiet", "rotate 90 degrees"],
            capture_output=True,
            text=True,
            check=True,
        )
        times.append(time.perf_counter() - t0)
        assert '"yaw":1.5708' in proc.stdout, proc.stdout
    return {"median_s": statistics.median(times), "max_s": max(times)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    args = parser.parse_args()
    planning, dispatch, cli = bench_planning(), bench_dispatch(), bench_cli()
    machine = (
        f"{platform.python_implementation()} {platform.python_version()}, "
        f"{platform.machine()}, 2 cores"
    )
    lines = [
        "<!-- core:start -->",
        "## Core (issue 2)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_core.py --write` "
        f"({machine}).",
        "",
        "| what | target | measured |",
        "|---|---|---|",
        f"| offline planning of a five-step sentence (median of 7x2000) | < 1 ms | "
        f"{planning['median_us']:.0f} us (best {planning['best_us']:.0f} us) |",
        f"| dispatch overhead per step, no-op skill (median of 5x1000 steps) | < 0.2 ms | "
        f"{dispatch['noop_median_ms']:.3f} ms |",
        f"| same, `body.stand` on a standing SimRobot (time scale 0) | - | "
        f"{dispatch['stand_median_ms']:.3f} ms |",
        f'| `shadowhound run --json "rotate 90 degrees"`, process start to output '
        f"(median of 7) | < 1 s | {cli['median_s'] * 1e3:.0f} ms (max "
        f"{cli['max_s'] * 1e3:.0f} ms) |",
        "",
        f'Five-step sentence: "{FIVE_STEPS}".',
        "<!-- core:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("core", section)


if __name__ == "__main__":
    main()
