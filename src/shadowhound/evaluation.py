"""Mission-case evaluation: run sentences on fresh simulated robots and check the outcome.

Case format (YAML list), see docs/missions.md:

    - mission: "walk forward 1 meter then turn left 90 degrees"
      expect: {success: true, x: 1.0, y: 0.0, yaw_deg: 90, posture: standing, moved: true}
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .agent import RobotAgent, RobotAgentConfig
from .config import MemoryConfig, ShadowHoundConfig
from .robot.sim import SimRobot

POSITION_TOLERANCE = 0.05  # metres
YAW_TOLERANCE_DEG = 3.0
_EXPECT_KEYS = {"success", "x", "y", "yaw_deg", "posture", "moved"}
_POSTURES = {"standing", "sitting", "lying"}


class CaseFileError(ValueError):
    """The case file is not in the mission-case format. The message says where and why."""


@dataclass(frozen=True)
class MissionCase:
    mission: str
    expect: dict[str, Any]


@dataclass
class CaseOutcome:
    case: MissionCase
    passed: bool
    failures: list[str] = field(default_factory=list)
    actual: dict[str, Any] = field(default_factory=dict)
    response: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"mission": self.case.mission, "expect": self.case.expect, "passed": self.passed,
                "failures": self.failures, "actual": self.actual, "response": self.response}


def load_cases(path: str | Path) -> list[MissionCase]:
    """Read and check a case file. Raises CaseFileError naming the bad entry."""
    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise CaseFileError(f"cannot read {str(path)!r}: {exc.strerror or exc}") from exc
    except yaml.YAMLError as exc:
        raise CaseFileError(f"{str(path)!r} is not valid YAML: {exc}") from exc
    if not isinstance(data, list):
        raise CaseFileError(f"{str(path)!r} must be a YAML list of cases, got "
                            f"{type(data).__name__}")
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
            raise CaseFileError(f"{where}: unknown expect keys {sorted(unknown)}; allowed: "
                                f"{sorted(_EXPECT_KEYS)}")
        for key in ("x", "y", "yaw_deg"):
            if key in expect and (isinstance(expect[key], bool)
                                  or not isinstance(expect[key], (int, float))):
                raise CaseFileError(f"{where}: expect.{key} must be a number")
        for key in ("success", "moved"):
            if key in expect and not isinstance(expect[key], bool):
                raise CaseFileError(f"{where}: expect.{key} must be true or false")
        if "posture" in expect and expect["posture"] not in _POSTURES:
            raise CaseFileError(f"{where}: expect.posture must be one of {sorted(_POSTURES)}")
        cases.append(MissionCase(entry["mission"], dict(expect)))
    return cases


def run_case(case: MissionCase, settings: ShadowHoundConfig) -> CaseOutcome:
    """Run one case on a fresh simulated robot at the origin, standing, time scale 0."""
    # Every case starts fresh: no history, no taught places from earlier runs.
    settings = settings.model_copy(update={"memory": MemoryConfig()})
    robot = SimRobot(settings.sim, time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    result = agent.execute_mission(case.mission)
    st = robot.get_state()
    actual = {"success": result.success, "x": round(st.x, 4), "y": round(st.y, 4),
              "yaw_deg": round(math.degrees(st.yaw), 2), "posture": st.posture.value,
              "moved": robot.received_motion}
    failures = []
    for key, want in case.expect.items():
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
    return CaseOutcome(case, not failures, failures, actual, result.response)


def run_cases(cases: list[MissionCase], settings: ShadowHoundConfig,
              on_case: Callable[[CaseOutcome], None] | None = None) -> list[CaseOutcome]:
    outcomes = []
    for case in cases:
        outcome = run_case(case, settings)
        outcomes.append(outcome)
        if on_case:
            on_case(outcome)
    return outcomes
