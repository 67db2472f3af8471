"""Cancel and e-stop while the mission waits on the model (issue 12, defect 4).

Run:  .venv/bin/python bench/bench_cancel.py [--write] [--trials N]
--write replaces the "cancel" section of bench/RESULTS.md with the figures measured now.

(i)  press to return: a scripted loopback server accepts the plan request and never answers
     (llm.timeout 30 s, max_retries 2: the defect waited 91.6 s); another thread presses
     cancel() or estop() while the request is in flight; the time from the press until
     execute_mission() returns, and the requests the server saw (1 = no retry).
(ii) the price of being cancellable: LLMPlanner.plan() against a zero-latency scripted server,
     with the mission's cancel event (the request runs on its own thread) and without it.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # tests.llm_server

from results import write_section  # noqa: E402
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot  # noqa: E402
from shadowhound.config import ShadowHoundConfig, load_config  # noqa: E402
from shadowhound.planning import PlanningContext  # noqa: E402
from shadowhound.planning.llm import LLMPlanner  # noqa: E402
from shadowhound.skills import default_registry  # noqa: E402
from shadowhound.state import RobotState  # noqa: E402
from tests.llm_server import ScriptedLLM, hang, json_plan  # noqa: E402

PLAN = [{"skill": "body.stand", "args": {}}, {"skill": "nav.move", "args": {"distance": 1.0}}]


def _settings(url: str, **llm: Any) -> ShadowHoundConfig:
    return load_config(
        "llamacpp",
        {"llm": {"base_url": url, "model": "m", **llm}, "memory": {"enabled": False}},
        environ={},
    )


def bench_press(press: str, trials: int) -> dict[str, Any]:
    seconds, requests, stopped, moved = [], [], 0, 0
    for _ in range(trials):
        with ScriptedLLM(models=("m",)) as srv:
            settings = _settings(srv.url, timeout=30, max_retries=2, check_on_start=False)
            robot = SimRobot(settings.sim, time_scale=0.0)
            agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
            agent.initialize()
            srv.script(hang(), hang(), hang())
            pressed: list[float] = []

            def press_in_flight(
                agent: RobotAgent = agent, srv: ScriptedLLM = srv, pressed: list[float] = pressed
            ) -> None:
                while not srv.requests:
                    time.sleep(0.001)
                time.sleep(0.05)
                pressed.append(time.perf_counter())
                getattr(agent, press)()

            presser = threading.Thread(target=press_in_flight, daemon=True)
            presser.start()
            result = agent.execute_mission("walk forward 1 meter")
            returned = time.perf_counter()
            presser.join()
            seconds.append(returned - pressed[0])
            time.sleep(0.6)  # longer than the first backoff: a retry would have been sent
            requests.append(len(srv.requests))
            stopped += result.status.value == "stopped"
            moved += bool(robot.received_motion)
            agent.release_estop()
            agent.cleanup()
    return {
        "median_ms": statistics.median(seconds) * 1e3,
        "max_ms": max(seconds) * 1e3,
        "requests": max(requests),
        "stopped": stopped,
        "moved": moved,
        "trials": trials,
    }


def bench_overhead(calls: int = 200, warmup: int = 20) -> dict[str, float]:
    """Both kinds of request alternate, call by call, so load on the machine hits both alike."""
    registry = default_registry()
    contexts = {
        name: PlanningContext(
            registry, RobotState(), dict(ShadowHoundConfig().places), cancelled=event
        )
        for name, event in (("inline", None), ("cancellable", threading.Event()))
    }
    times: dict[str, list[float]] = {name: [] for name in contexts}
    with ScriptedLLM(models=("m",)) as srv:
        planner = LLMPlanner(_settings(srv.url, check_on_start=False))
        srv.script(*[json_plan(PLAN) for _ in range(2 * (warmup + calls))])
        for i in range(warmup + calls):
            for name, context in contexts.items():
                t0 = time.perf_counter()
                planner.plan("stand up and walk forward 1 meter", context)
                if i >= warmup:
                    times[name].append(time.perf_counter() - t0)
    out = {}
    for name, values in times.items():
        out[name] = statistics.median(values) * 1e3
        out[name + "_min"] = min(values) * 1e3
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--trials", type=int, default=10, help="presses of each kind")
    args = parser.parse_args()
    cancel = bench_press("cancel", args.trials)
    estop = bench_press("estop", args.trials)
    overhead = bench_overhead()
    lines = [
        "<!-- cancel:start -->",
        "## Cancel and e-stop while waiting on the model (issue 12, `bench/bench_cancel.py`)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_cancel.py --write` "
        f"(CPython {platform.python_version()}, {platform.machine()}); a loopback server "
        "that accepts the plan request and never answers, llm.timeout 30 s, max_retries 2 "
        "(before the fix the mission waited 91.6 s and ended failed).",
        "",
        "| what | measured |",
        "|---|---|",
    ]
    for name, row in (("cancel()", cancel), ("estop()", estop)):
        lines.append(
            f"| {name} during planning: press to `execute_mission` returning "
            f"({row['trials']} presses) | median {row['median_ms']:.0f} ms, max "
            f"{row['max_ms']:.0f} ms; stopped {row['stopped']}/{row['trials']}, robot moved "
            f"{row['moved']}, requests the server saw: {row['requests']} |"
        )
    lines += [
        f"| `LLMPlanner.plan()` per round trip, zero-latency server, 200 calls of each, "
        f"alternating: without / with the cancel event (own thread) | "
        f"median {overhead['inline']:.2f} ms / "
        f"{overhead['cancellable']:.2f} ms; min {overhead['inline_min']:.2f} ms / "
        f"{overhead['cancellable_min']:.2f} ms |",
        "<!-- cancel:end -->",
    ]
    section = "\n".join(lines) + "\n"
    print(section)
    if args.write:
        write_section("cancel", section)


if __name__ == "__main__":
    main()
