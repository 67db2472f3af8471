"""Tricks come from the backend (issue 25): a robot's `tricks` are what `body.sport` offers,
what the offline planner reads, and what the model's plan schema allows; a robot without
tricks is offered no `body.sport` at all."""

from __future__ import annotations

import json

import pytest

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig, load_config
from shadowhound.plan import SkillCall
from shadowhound.planning import make_planner
from shadowhound.planning.prompts import stable_prefix
from shadowhound.planning.schema import plan_schema
from shadowhound.robot.factory import tricks_of
from shadowhound.robot.go2 import api as go2_api
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.robot_config import Go2EduRobotSettings, Go2RobotSettings, SimRobotSettings
from shadowhound.skills import SkillRegistry, SkillValidationError, default_registry
from tests.robot.test_base import Minimal

AI_ONLY = {n for n, t in go2_api.TRICKS.items() if t.api_id in go2_api.AI_MODE_TRICKS}


def agent_on(robot: object) -> RobotAgent:
    settings = ShadowHoundConfig()
    settings.memory.enabled = False
    return RobotAgent(RobotAgentConfig(robot=robot, settings=settings))  # type: ignore[arg-type]


def test_each_backend_says_its_tricks_before_it_is_built() -> None:
    every = set(go2_api.TRICKS)
    assert set(tricks_of(SimRobotSettings())) == every == set(SimRobot(time_scale=0).tricks)
    assert set(tricks_of(Go2RobotSettings(firmware_tricks=True))) == every
    normal = every - AI_ONLY
    assert "backflip" in AI_ONLY and "hello" in normal
    assert set(tricks_of(Go2RobotSettings())) == normal  # firmware tricks are off by default
    assert set(tricks_of(Go2EduRobotSettings())) == normal  # unitree_ros2: no "ai" mode


def test_the_registry_offers_exactly_the_robots_tricks() -> None:
    assert default_registry().tricks() == frozenset(go2_api.TRICKS)  # the default robot's
    assert "body.sport" not in default_registry({})
    assert default_registry({}).tricks() == frozenset()
    normal = tricks_of(Go2RobotSettings())
    registry = default_registry(normal)
    assert registry.tricks() == frozenset(normal)
    ok = registry.validate(SkillCall("body.sport", {"trick": "hello"}))
    assert ok.args.trick == "hello"  # type: ignore[attr-defined]
    with pytest.raises(SkillValidationError, match="backflip"):
        registry.validate(SkillCall("body.sport", {"trick": "backflip"}))


def test_an_agent_on_a_robot_without_tricks_offers_none() -> None:
    robot = Minimal()
    agent = agent_on(robot)
    assert "body.sport" not in agent.registry
    result = agent.execute_mission("do a backflip")
    assert not result.success
    assert "this robot does not perform the backflip trick (its tricks: none)" in result.response
    assert robot.stops <= 1  # nothing was run
    wave = agent.execute_mission("wave")
    assert not wave.success and "does not perform the hello trick" in wave.response


def test_a_greeting_on_a_robot_without_tricks_is_said_without_the_wave() -> None:
    planner = make_planner(load_config("offline", environ={}), tricks=frozenset())
    plan = planner.plan("say hello")
    assert [s.skill for s in plan.steps] == ["voice.say"]
    with_wave = make_planner(load_config("offline", environ={}), tricks={"hello"}).plan("say hello")
    assert [s.skill for s in with_wave.steps] == ["voice.say", "body.sport"]


def test_the_agent_takes_the_tricks_of_the_backend_its_profile_chooses() -> None:
    settings = ShadowHoundConfig(robot="go2")
    agent = RobotAgent(settings)  # the Go2 is not built until a mission needs it
    assert agent.registry.tricks() == frozenset(go2_api.TRICKS) - AI_ONLY
    settings = ShadowHoundConfig(robot={"type": "go2", "firmware_tricks": True})
    assert RobotAgent(settings).registry.tricks() == frozenset(go2_api.TRICKS)


@pytest.mark.parametrize("style", ["plan", "strict"])
def test_the_model_is_offered_only_the_robots_tricks(style: str) -> None:
    def offered(registry: SkillRegistry) -> str:
        if style == "plan":  # the prompt's catalogue (the compact schema names no tricks)
            return stable_prefix(registry, style="plan")
        return json.dumps(plan_schema(registry, "json_schema", "strict"))

    with_tricks = offered(default_registry())
    assert "body.sport" in with_tricks and "backflip" in with_tricks
    normal = offered(default_registry(tricks_of(Go2RobotSettings())))
    assert "body.sport" in normal and "backflip" not in normal and "hello" in normal
    none = offered(default_registry({}))
    assert "body.sport" not in none


def test_a_robot_of_its_own_names_its_tricks() -> None:
    class Dancer(Minimal):
        tricks = {"spin_around": go2_api.Trick("spin_around", 0, "spin on the spot", 2.0)}

        def __init__(self) -> None:
            super().__init__()
            self.done: list[str] = []

        def perform(self, trick: str) -> None:
            self.done.append(trick)

    robot = Dancer()
    agent = agent_on(robot)
    assert agent.registry.tricks() == {"spin_around"}
    result = agent.execute_mission("do the spin around trick")
    assert result.success, result.response
    assert robot.done == ["spin_around"]
