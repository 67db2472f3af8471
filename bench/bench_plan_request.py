"""Size of the model planner's first request (issue 26: messages + schema at most 5,000).

Run:  .venv/bin/python bench/bench_plan_request.py [--write]
--write replaces the "plan-request" section of bench/RESULTS.md with the figures measured now.

For each backend's schema dialect, an agent plans "stand up and walk forward 1 meter" with the
model alone (hybrid off, plan mode, the default compact plan schema; the strict one for the
comparison column) against a scripted
OpenAI-compatible server on loopback, which records the request. Measured: characters of the
compact JSON of its `messages` and of its `response_format` (the plan schema as sent).
Characters, not tokens: about 4 make a token for English and JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # tests.llm_server

from results import write_section  # noqa: E402
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config  # noqa: E402
from tests.llm_server import ScriptedLLM, json_plan  # noqa: E402

MISSION = "stand up and walk forward 1 meter"
TARGET = 5000
BACKENDS = {
    "llamacpp": "llamacpp",
    "vllm": "json_schema",
    "ollama": "json_schema",
    "openai": "openai",
}
# The same measure at a9427aa, before issue 26's compaction (and before the refusal step).
BEFORE = {
    "llamacpp": (3400, 6056),
    "vllm": (3400, 6928),
    "ollama": (3400, 6928),
    "openai": (3400, 7161),
}


def first_request(backend: str, style: str = "compact") -> dict[str, Any]:
    with ScriptedLLM(models=("m",), ollama_tags=["m:latest"]) as srv:
        srv.script(json_plan([{"skill": "body.stand", "args": {}}]))
        llm = {
            "base_url": srv.url,
            "model": "m",
            "check_on_start": False,
            "hybrid": False,
            "plan_format": "json_schema",
            "max_retries": 0,
            "plan_schema": style,
        }
        settings = load_config(
            backend, {"llm": llm, "memory": {"enabled": False}}, environ={"OPENAI_API_KEY": "x"}
        )
        robot = SimRobot(settings.sim, time_scale=0.0)
        agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
        agent.initialize()
        agent.execute_mission(MISSION)
        agent.cleanup()
        return srv.requests[0]


def size(value: Any) -> int:
    return len(json.dumps(value, separators=(",", ":")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    args = parser.parse_args()
    os.environ.setdefault("HOME", tempfile.mkdtemp())  # no user profile leaks in
    rows = []
    for backend, dialect in BACKENDS.items():
        request = first_request(backend)
        messages, schema = size(request["messages"]), size(request["response_format"])
        strict = first_request(backend, "strict")
        strict_total = size(strict["messages"]) + size(strict["response_format"])
        before = sum(BEFORE[backend])
        rows.append(
            f"| {backend} ({dialect}) | {messages} | {schema} | {messages + schema} "
            f"| {'yes' if messages + schema <= TARGET else 'no'} | {strict_total} | {before} |"
        )
        print(f"{backend:9} messages {messages:5} schema {schema:5} total {messages + schema}")
    section = "\n".join(
        [
            "<!-- plan-request:start -->",
            "## The model planner's first request",
            "",
            f'Measured with `python bench/bench_plan_request.py --write`: "{MISSION}", plan mode, '
            "the model alone (hybrid off), the default (compact) plan schema, on a scripted server "
            "on loopback; characters of compact JSON (about 4 make a token). NASA-JPL ROSA's "
            "first request for the same sentence is 23,042 (issue 26's measure).",
            "",
            f"| backend (schema dialect) | messages | schema | total | within {TARGET:,} "
            "(issue 26) | total with `plan_schema: strict` | total at a9427aa |",
            "|---|---|---|---|---|---|---|",
            *rows,
            "",
            "What changed since a9427aa: the schema gained the refusal step and the plan's "
            "`conditions` (watches and guards), the registry nav.follow. The default plan "
            "schema is now `compact` (`llm.plan_schema`): a step is one of the skills' names "
            "and `args` holds arguments some skill takes, typed; which skill takes which, the "
            "required ones, ranges and the tricks are the registry's checks, with a repair "
            "turn. The `strict` style (each skill with exactly its own arguments) is still "
            "there: about 5,800-7,000 characters of schema alone. The prompt's skill lines "
            "name the arguments and let the description say what they mean (each thing said "
            "once), and OpenAI, whose model is shown the schema, is not told the JSON's shape "
            "again in words. The prompt's skill catalogue (about 1,900 characters) is what a "
            "small local model, which never sees the schema, plans from.",
            "<!-- plan-request:end -->",
        ]
    )
    if args.write:
        write_section("plan-request", section)


if __name__ == "__main__":
    main()
