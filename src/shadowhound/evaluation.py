"""Mission-case evaluation: run sentences on fresh simulated robots and check the outcome.

Case format (YAML list), see docs/missions.md:

    - mission: "walk forward 1 meter then turn left 90 degrees"
      expect: {success: true, x: 1.0, y: 0.0, yaw_deg: 90, posture: standing, moved: true}

A case may give its own `scene` (a world as in `World.from_dict`; default: the simulator's
default scene) and `start` pose ([x, y] or [x, y, yaw_deg]). Every case also fails when the
robot's body overlapped an object or a wall at any moment (the simulator's true path).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .agent import RobotAgent, RobotAgentConfig
from .config import MemoryConfig, ShadowHoundConfig
from .errors import CaseFileError, ConfigError
from .plan import Usage
from .robot.sim.robot import SimRobot
from .robot.sim.scene import World
from .robot.sim.sensors import penetration

POSITION_TOLERANCE = 0.05  # metres
YAW_TOLERANCE_DEG = 3.0
_EXPECT_KEYS = {"success", "x", "y", "yaw_deg", "posture", "moved", "near"}
_POSTURES = {"standing", "sitting", "lying"}


@dataclass(frozen=True)
class MissionCase:
    mission: str
    expect: dict[str, Any]
    scene: World | None = None  # None: the simulator's default scene
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y (metres), yaw (radians)


@dataclass
class CaseOutcome:
    case: MissionCase
    passed: bool
    failures: list[str] = field(default_factory=list)
    actual: dict[str, Any] = field(default_factory=dict)
    response: str = ""
    usage: Usage = field(default_factory=Usage)
    planning_seconds: float = 0.0  # wall time spent planning (and re-planning)
    planned_by: str = ""  # offline | llm | "" (no plan)

    def to_dict(self) -> dict[str, Any]:
        return {
            "mission": self.case.mission,
            "expect": self.case.expect,
            "passed": self.passed,
            "failures": self.failures,
            "actual": self.actual,
            "response": self.response,
            "usage": self.usage.to_dict(),
            "planning_seconds": round(self.planning_seconds, 6),
            "planned_by": self.planned_by,
        }


@dataclass(frozen=True)
class Scorecard:
    """How one planner did on a case file: the figures `shadowhound eval` compares."""

    planner: str
    cases: int
    passed: int
    model_calls: int  # round trips to the model, all cases
    prompt_tokens: int
    completion_tokens: int
    invalid_plans: int  # model replies that failed validation (each went to repair)
    offline_planned: int  # cases the offline rules planned (no model call)
    latency_p50: float  # planning seconds per case
    latency_p95: float

    @property
    def pass_rate(self) -> float:
        return self.passed / self.cases if self.cases else 0.0

    @property
    def calls_per_mission(self) -> float:
        return self.model_calls / self.cases if self.cases else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "planner": self.planner,
            "cases": self.cases,
            "passed": self.passed,
            "pass_rate": round(self.pass_rate, 4),
            "model_calls": self.model_calls,
            "calls_per_mission": round(self.calls_per_mission, 3),
            "prompt_tokens": self.prompt_tokens,
            "completion_tokens": self.completion_tokens,
            "invalid_plans": self.invalid_plans,
            "offline_planned": self.offline_planned,
            "latency_p50_ms": round(self.latency_p50 * 1e3, 3),
            "latency_p95_ms": round(self.latency_p95 * 1e3, 3),
        }


# What a planner spec "BACKEND[:OPTION...]" may say after the backend, as llm settings.
PLANNER_OPTIONS: dict[str, dict[str, Any]] = {
    "hybrid": {"hybrid": True},
    "llm": {"hybrid": False},  # every mission to the model
    "json_schema": {"plan_format": "json_schema"},
    "plain": {"plan_format": "plain"},
    "tools": {"plan_format": "tools"},
    "react": {"mode": "react"},
}


def planner_options(spec: str) -> tuple[str, dict[str, Any]]:
    """`"llamacpp:llm:plain"` -> ("llamacpp", llm settings). Raises ConfigError if unknown."""
    backend, *options = spec.split(":")
    llm: dict[str, Any] = {}
    for option in options:
        if option not in PLANNER_OPTIONS:
            raise ConfigError(
                f"unknown planner option {option!r} in {spec!r}; allowed after "
                f"the backend: {', '.join(PLANNER_OPTIONS)}"
            )
        llm.update(PLANNER_OPTIONS[option])
    return backend, llm


def scorecard(planner: str, outcomes: list[CaseOutcome]) -> Scorecard:
    times = sorted(o.planning_seconds for o in outcomes) or [0.0]
    p95 = statistics.quantiles(times, n=20, method="inclusive")[18] if len(times) > 1 else times[0]
    return Scorecard(
        planner=planner,
        cases=len(outcomes),
        passed=sum(o.passed for o in outcomes),
        model_calls=sum(o.usage.round_trips for o in outcomes),
        prompt_tokens=sum(o.usage.prompt_tokens for o in outcomes),
        completion_tokens=sum(o.usage.completion_tokens for o in outcomes),
        invalid_plans=sum(o.usage.invalid_plans for o in outcomes),
        offline_planned=sum(o.planned_by == "offline" for o in outcomes),
        latency_p50=statistics.median(times),
        latency_p95=p95,
    )


def load_cases(path: str | Path) -> list[MissionCase]:
    """Read and check a case file. Raises CaseFileError naming the bad entry."""
    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise CaseFileError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from exc
    except yaml.YAMLError as exc:
        raise CaseFileError(f"{str(path)!r} is not valid YAML: {exc}") from exc
    if not isinstance(data, list):
        raise CaseFileError(
            f"{str(path)!r} must be a YAML list of cases, got {type(data).__name__}"
        )
    cases = []
    for i, entry in enumerate(data, start=1):
        where = f"case {i} in {str(path)!r}"
        if not isinstance(entry, dict) or "mission" not in entry:
            raise CaseFileError(f"{where} must be a mapping with a 'mission' key")
        if not isinstance(entry["mission"], str):
            raise CaseFileError(f"{where}: 'mission' must be text")
        expect = entry.get("expect") or {}
        if not isinstance(expect, dict):
            raise CaseFileError(f"{where}: 'expect' must be a mapping")
        unknown = set(expect) - _EXPECT_KEYS
        if unknown:
            raise CaseFileError(
                f"{where}: unknown expect keys {sorted(unknown)}; allowed: {sorted(_EXPECT_KEYS)}"
            )
        for key in ("x", "y", "yaw_deg"):
            if key in expect and (
                isinstance(expect[key], bool) or not isinstance(expect[key], (int, float))
            ):
                raise CaseFileError(f"{where}: expect.{key} must be a number")
        for key in ("success", "moved"):
            if key in expect and not isinstance(expect[key], bool):
                raise CaseFileError(f"{where}: expect.{key} must be true or false")
        if "near" in expect:
            _check_near(expect["near"], where)
        if "posture" in expect and expect["posture"] not in _POSTURES:
            raise CaseFileError(f"{where}: expect.posture must be one of {sorted(_POSTURES)}")
        cases.append(MissionCase(entry["mission"], dict(expect), *_scene_and_start(entry, where)))
    return cases


def _check_near(near: Any, where: str) -> None:
    if (
        not isinstance(near, dict)
        or set(near) != {"x", "y", "within"}
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in near.values()
        )
        or near["within"] <= 0
    ):
        raise CaseFileError(
            f"{where}: expect.near must be {{x: metres, y: metres, within: "
            f"metres > 0}}, got {near!r}"
        )


def _scene_and_start(
    entry: dict[str, Any], where: str
) -> tuple[World | None, tuple[float, float, float]]:
    scene = None
    if entry.get("scene") is not None:
        try:
            scene = World.from_dict(entry["scene"])
        except ValueError as exc:
            raise CaseFileError(f"{where}: scene: {exc}") from exc
    raw = entry.get("start", [0.0, 0.0])
    if (
        not isinstance(raw, list)
        or len(raw) not in (2, 3)
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in raw
        )
    ):
        raise CaseFileError(
            f"{where}: start must be [x, y] or [x, y, yaw_deg] in numbers, got {raw!r}"
        )
    yaw = math.radians(raw[2]) if len(raw) == 3 else 0.0
    return scene, (float(raw[0]), float(raw[1]), yaw)


def run_case(case: MissionCase, settings: ShadowHoundConfig) -> CaseOutcome:
    """Run one case on a fresh simulated robot at the origin, standing, time scale 0."""
    # Every case starts fresh: no history, no taught places from earlier runs.
    settings = settings.model_copy(update={"memory": MemoryConfig()})
    robot = SimRobot(settings.sim, time_scale=0.0, world=case.scene)
    robot.reset(*case.start)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    began = robot.now()
    result = agent.execute_mission(case.mission)
    st = robot.get_state()
    actual = {
        "success": result.success,
        "x": round(st.x, 4),
        "y": round(st.y, 4),
        "yaw_deg": round(math.degrees(st.yaw), 2),
        "posture": st.posture.value,
        "moved": robot.received_motion,
    }
    # Measured, not expected: how far the body walked, in how long, after how many re-plans.
    path = robot.true_path
    actual["path_length"] = round(
        sum(math.dist(a[1:], b[1:]) for a, b in zip(path, path[1:], strict=False)), 3
    )
    actual["seconds"] = round(robot.now() - began, 2)
    actual["replans"] = sum(s.output.count("re-planned") for s in result.steps)
    failures = []
    depth, what = max(
        (penetration(robot.world, x, y, robot.config.body_radius) for _t, x, y in path),
        key=lambda d: d[0],
    )
    if depth > 1e-9:
        failures.append(f"the body overlapped {what} by {depth:.3f} m")
    for key, want in case.expect.items():
        if key == "near":
            off = math.hypot(st.x - want["x"], st.y - want["y"])
            if off > want["within"]:
                failures.append(
                    f"near: expected within {want['within']:g} m of "
                    f"({want['x']:g}, {want['y']:g}), ended {off:.2f} m away"
                )
            continue
        got = actual[key]
        if key in ("x", "y"):
            ok = abs(got - want) <= POSITION_TOLERANCE
        elif key == "yaw_deg":
            ok = abs((got - want + 180.0) % 360.0 - 180.0) <= YAW_TOLERANCE_DEG
        else:
            ok = got == want
        if not ok:
            failures.append(f"{key}: expected {want!r}, got {got!r}")
    agent.cleanup()
    return CaseOutcome(
        case=case,
        passed=not failures,
        failures=failures,
        actual=actual,
        response=result.response,
        usage=result.usage,
        planning_seconds=result.timing.agent_duration,
        planned_by=result.plan.planned_by if result.plan else "",
    )


def run_cases(
    cases: list[MissionCase],
    settings: ShadowHoundConfig,
    on_case: Callable[[CaseOutcome], None] | None = None,
) -> list[CaseOutcome]:
    outcomes = []
    for case in cases:
        outcome = run_case(case, settings)
        outcomes.append(outcome)
        if on_case:
            on_case(outcome)
    return outcomes
