"""Commands that run missions: `run` (with progress, approvals, dry runs) and `eval`; `chat`
is in chat.py and shows a mission's steps with `progress` from here."""

from __future__ import annotations

import argparse
import math
import sys
import threading
from typing import TYPE_CHECKING, Any, TextIO

from .. import events as ev
from .. import jsonout
from ..approval import ApprovalRequest
from ..config import ShadowHoundConfig
from ..exit_codes import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE
from ..result import StepStatus
from ..worker import MissionJob, MissionWorker
from ._base import make_agent, print_json, report_error

if TYPE_CHECKING:
    from ..skills import SkillRegistry

# -- run -----------------------------------------------------------------------------------


def progress(stream: TextIO, registry: SkillRegistry) -> ev.Listener:
    """Each step as it starts and ends. A step whose output answers the user (a skill that
    `reports`: a view, a status) is only marked answered: the response says the answer."""

    def show(event: ev.MissionEvent) -> None:
        if isinstance(event, ev.MissionStarted):
            print(f"mission: {event.mission!r}", file=stream)
        elif isinstance(event, ev.PlanReady):
            print(f"plan: {len(event.plan.steps)} step(s)", file=stream)
        elif isinstance(event, ev.StepStarted):
            step = event.step
            args = ", ".join(f"{k}={v}" for k, v in step.args.items())
            watching = f" {step.watching()}" if step.watches else ""
            print(f"  [{step.index}] {step.skill}({args}){watching} ...", file=stream, flush=True)
        elif isinstance(event, ev.StepFinished):
            step = event.step
            ok = step.status is StepStatus.SUCCEEDED
            mark = "ok" if ok else step.status.value.upper()
            skill = registry.find(step.skill)
            detail = (
                step.error if not ok else "answered" if skill and skill.reports else step.output
            )
            print(
                f"  [{step.index}] {mark}: {detail} ({step.robot_duration:.1f} s robot time)",
                file=stream,
                flush=True,
            )
        stream.flush()

    return show


def _approver(agent: Any, ask: bool) -> ev.Listener:
    """Answer approval requests: with --yes at once, else by asking on the terminal."""

    def decide(request: ApprovalRequest) -> None:
        if not ask:
            agent.approve(request.request_id)
            return
        print("approval needed: " + "; ".join(request.reasons), file=sys.stderr)
        print(f"approve within {request.timeout:g} s? [y/N] ", end="", file=sys.stderr, flush=True)
        answer = sys.stdin.readline().strip().lower()
        if answer in ("y", "yes"):
            agent.approve(request.request_id)
        else:
            agent.reject(request.request_id, "declined at the terminal")

    def on_event(event: ev.MissionEvent) -> None:
        if isinstance(event, ev.ApprovalRequired):
            # Ask on another thread: the mission thread waits with its time-out meanwhile.
            threading.Thread(target=decide, args=(event.request,), daemon=True).start()

    return on_event


def cmd_run(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    agent = make_agent(settings)
    if not args.dry_run:
        if not args.quiet:
            agent.add_listener(progress(sys.stderr, agent.registry))
        if args.yes or sys.stdin.isatty():
            agent.enable_approvals()
            agent.add_listener(_approver(agent, ask=not args.yes))
    job = MissionJob(args.mission, source="cli", dry_run=args.dry_run)
    interrupted = _run_on_worker(agent, job)
    result = job.result
    agent.cleanup()
    if job.dropped is not None:  # the worker caught a crash: a bug, not a mission failure
        return report_error(
            "internal",
            f"{job.dropped}; the robot was stopped",
            EXIT_FAILED,
            json_out=args.json,
            mission=args.mission,
        )
    if result is None:
        return report_error(
            "interrupted",
            "the robot was stopped",
            EXIT_INTERRUPTED,
            json_out=args.json,
            mission=args.mission,
        )
    if args.dry_run:
        return _show_dry_run(result, args)
    code = EXIT_INTERRUPTED if interrupted else EXIT_OK if result.success else EXIT_FAILED
    if args.json:
        print_json(_answer(result, code))
    else:
        st = result.robot
        print(result.response)
        if st is not None:  # None only when the robot could not be read at all
            print(
                f"robot: x={st.x:.3f} m y={st.y:.3f} m yaw={st.yaw:.4f} rad "
                f"({round(math.degrees(st.yaw), 2)} deg) posture={st.posture.value} "
                f"battery={st.battery_text}"
            )
    return code


def _run_on_worker(agent: Any, job: MissionJob) -> bool:
    """Run `job` on a mission worker, as every interface does; True if Ctrl-C stopped it.

    This thread stays free, so that Ctrl-C here can stop the robot at once. The job's end is
    an Event, not Thread.join: a join interrupted by Ctrl-C can mark a live thread finished
    (CPython 3.11), and the result would be lost. Ctrl-C may land while the worker starts.
    """
    worker: MissionWorker | None = None
    try:
        worker = MissionWorker(agent)  # the command line reports the mission after it ends
        worker.submit(job)  # the only job of a fresh worker: never refused
        while not job.done.wait(0.1):
            pass
    except KeyboardInterrupt:
        if worker is not None:
            worker.estop()
        else:  # no job was given to a worker yet: only the latch is left to set
            agent.estop()
        job.done.wait(5.0)
        return True
    finally:
        if worker is not None:  # a mission still running after Ctrl-C is not waited for
            worker.stop(timeout=5.0 if job.done.is_set() else 0.0)
    return False


def _answer(result: Any, code: int) -> dict[str, Any]:
    """A result as the JSON answer, with the exit code the command ends with."""
    answer: dict[str, Any] = result.to_dict()
    answer["exit_code"] = code
    return answer


def _show_dry_run(result: Any, args: argparse.Namespace) -> int:
    code = EXIT_OK if result.success else EXIT_FAILED
    if args.json:
        print_json(_answer(result, code))
    else:
        for step in result.steps:
            params = ", ".join(f"{k}={v}" for k, v in step.args.items())
            watching = f" {step.watching()}" if step.watches else ""
            print(f"  [{step.index}] {step.skill}({params}){watching}")
        points = result.predicted_path
        path = " -> ".join(f"({p.x:.2f}, {p.y:.2f})" for p in points)
        if path:
            # With a map, nav.goto's planned path around obstacles: every corner is a waypoint.
            legs = zip(points, points[1:], strict=False)
            length = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in legs)
            print(f"predicted path ({length:.2f} m, {len(points)} waypoints): {path}")
        for note in result.plan.notes if result.plan else []:
            print(f"note: {note}")  # e.g. how a misspelt word was read
        print(result.response)
    return code


# -- eval ----------------------------------------------------------------------------------------


def cmd_eval(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    """Run a case file with one planner, or several side by side (`--backend` repeated)."""
    from ..errors import CaseFileError
    from ..evaluation import load_cases, run_cases, scorecard
    from . import _settings

    try:
        cases = load_cases(args.file)
    except CaseFileError as exc:
        print(f"shadowhound: {exc}", file=sys.stderr)
        return EXIT_USAGE
    specs = args.backend if isinstance(args.backend, list) else [None]
    planners = [
        (spec or settings.backend, _settings(args, spec) if spec else settings) for spec in specs
    ]  # every spec checked before the first case runs
    several = len(planners) > 1

    reports = []
    for label, planner_settings in planners:

        def show(outcome: Any, label: str = label) -> None:
            if args.json:
                return
            mark = "PASS" if outcome.passed else "FAIL"
            print(f"{mark}  {f'[{label}] ' if several else ''}{outcome.case.mission!r}")
            for failure in outcome.failures:
                print(f"      {failure}  [{outcome.response}]")

        outcomes = run_cases(cases, planner_settings, on_case=show)
        card = scorecard(label, outcomes)
        reports.append((card, outcomes))
        if not args.json:
            print(
                f"{f'{label}: ' if several else ''}{card.passed}/{card.cases} cases passed "
                f"({100 * card.pass_rate:.1f}%)"
            )
    if args.json:
        jsonout.dump(_eval_json(reports, several), sys.stdout, indent=2)
        sys.stdout.write("\n")
    elif several:
        print(scorecard_table([card for card, _ in reports]))
    ok = all(card.passed == card.cases and card.cases for card, _ in reports)
    return EXIT_OK if ok else EXIT_FAILED


def _eval_json(reports: list[tuple[Any, list[Any]]], several: bool) -> dict[str, Any]:
    def one(card: Any, outcomes: list[Any]) -> dict[str, Any]:
        return {
            "total": card.cases,
            "passed": card.passed,
            "failed": card.cases - card.passed,
            "pass_rate": round(card.pass_rate, 4),
            "scorecard": card.to_dict(),
            "cases": [o.to_dict() for o in outcomes],
        }

    if several:
        return {"planners": [one(card, outcomes) for card, outcomes in reports]}
    return one(*reports[0])


def scorecard_table(cards: list[Any]) -> str:
    """One row per planner: pass rate, model calls, tokens, planning latency, invalid plans."""
    head = [
        "planner",
        "passed",
        "model calls/mission",
        "planned offline",
        "prompt tokens",
        "completion tokens",
        "planning p50 ms",
        "planning p95 ms",
        "invalid plans",
    ]
    rows = [
        [
            c.planner,
            f"{c.passed}/{c.cases} ({100 * c.pass_rate:.0f}%)",
            f"{c.calls_per_mission:.2f}",
            f"{c.offline_planned}/{c.cases}",
            str(c.prompt_tokens),
            str(c.completion_tokens),
            f"{c.latency_p50 * 1e3:.1f}",
            f"{c.latency_p95 * 1e3:.1f}",
            str(c.invalid_plans),
        ]
        for c in cards
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)
