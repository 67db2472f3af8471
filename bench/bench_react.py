"""React mode with a real model: how long the bounded loop takes (moved here from the test).

Run:  .venv/bin/python bench/bench_react.py [--write] [--runs N]
--write replaces the "llm-react" section of bench/RESULTS.md with the figures measured now.

`shadowhound run --mode react --json "stand up and walk forward 1 meter"` as
tests/test_llm_llamacpp.py::test_react_mode_is_bounded runs it (llama.cpp's server with
SmolLM2-135M-Instruct on 2 threads, react_max_steps 3, react_token_budget 4000, max_tokens 256,
hybrid off): process start to its JSON, the skill calls, round trips and tokens, per run. The
test asserts only the bounds (steps, tokens); the time is this benchmark's figure, since a
loaded machine makes CPU inference as slow as it likes.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # tests.test_llm_llamacpp

from results import write_section  # noqa: E402
from tests.home import home_env  # noqa: E402
from tests.test_llm_llamacpp import (  # noqa: E402
    LLM_ENV,
    MISSION,
    MISSION_TIMEOUT,
    REACT_MAX_STEPS,
    REACT_TOKEN_BUDGET,
    LlamaServer,
    find_model,
    llm_args,
    missing_requirements,
    shadowhound,
)


def bench(runs: int) -> list[dict[str, Any]]:
    problems = missing_requirements()
    if problems:
        sys.exit("bench_react: needs " + " and ".join(problems))
    model = find_model()
    assert model is not None
    with (
        tempfile.TemporaryDirectory(prefix="bench-react-home-") as home,
        tempfile.NamedTemporaryFile(prefix="llama-server-", suffix=".log") as log,
    ):
        os.environ.update(home_env(Path(home)))  # the runs' history goes there, not to ~
        with LlamaServer(model, log) as srv:
            return [_run(srv) for _ in range(runs)]


def _run(srv: LlamaServer) -> dict[str, Any]:
    started = time.perf_counter()
    proc = shadowhound(
        "run",
        *llm_args(srv),
        "--mode",
        "react",
        "--json",
        MISSION,
        timeout=MISSION_TIMEOUT,
        SHADOWHOUND_LLM__REACT_MAX_STEPS=str(REACT_MAX_STEPS),
        SHADOWHOUND_LLM__REACT_TOKEN_BUDGET=str(REACT_TOKEN_BUDGET),
        **LLM_ENV,
    )
    seconds = time.perf_counter() - started
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    usage = out["usage"]
    run = {
        "seconds": seconds,
        "exit": proc.returncode,
        "steps": len(out["steps"]),
        "round_trips": usage["round_trips"],
        "tokens": usage["prompt_tokens"] + usage["completion_tokens"],
    }
    print(run, file=sys.stderr)
    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--runs", type=int, default=5, help="missions to run (default 5)")
    args = parser.parse_args()
    with open("/proc/loadavg") as f:
        load_before = f.read().split()[0]
    runs = bench(args.runs)
    with open("/proc/loadavg") as f:
        load_after = f.read().split()[0]
    seconds = [r["seconds"] for r in runs]
    machine = (
        f"{platform.python_implementation()} {platform.python_version()}, "
        f"{platform.machine()}, 2 cores"
    )
    lines = [
        "<!-- llm-react:start -->",
        "## React mode with a real model (`bench/bench_react.py`)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_react.py --write` "
        f"({machine}; load average {load_before} before, {load_after} after: the machine was "
        f'shared). `shadowhound run --mode react --json "{MISSION}"` against llama.cpp\'s '
        "server with SmolLM2-135M-Instruct, react_max_steps "
        f"{REACT_MAX_STEPS}, react_token_budget {REACT_TOKEN_BUDGET}, max_tokens "
        f"{LLM_ENV['SHADOWHOUND_LLM__MAX_TOKENS']}, as "
        "`tests/test_llm_llamacpp.py::test_react_mode_is_bounded` runs it (that test checks "
        "the bounds; it no longer times the run, which was asserted under 60 s).",
        "",
        "| what | measured |",
        "|---|---|",
        f"| process start to its JSON ({len(runs)} runs) | median "
        f"{statistics.median(seconds):.1f} s, min {min(seconds):.1f} s, max "
        f"{max(seconds):.1f} s |",
        "| per run: seconds, exit code, skill calls, round trips, prompt + completion tokens | "
        + "; ".join(
            f"{r['seconds']:.1f} s, {r['exit']}, {r['steps']}, {r['round_trips']}, {r['tokens']}"
            for r in runs
        )
        + " |",
        "<!-- llm-react:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("llm-react", section)


if __name__ == "__main__":
    main()
