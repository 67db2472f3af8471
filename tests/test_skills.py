import math
import threading

import pytest

from shadowhound import SkillCall, SkillValidationError, default_registry, units
from shadowhound.config import ShadowHoundConfig
from shadowhound.skills import (
    MissionCancelled,
    PlanEnv,
    SkillArgs,
    SkillContext,
    SkillError,
    SkillTimeout,
)
from shadowhound.skills.arguments import Count, Length, argument_kind, is_numeric
from shadowhound.skills.context import robot_belief


@pytest.fixture
def registry():
    return default_registry()


def run(registry, robot, skill, settings=None, **args):
    settings = settings or ShadowHoundConfig()
    call = registry.validate(SkillCall(skill, args))
    env = PlanEnv(settings, robot.get_state().pose, belief=robot_belief(robot))
    ctx = SkillContext(robot, env, threading.Event(), camera=robot.get_camera_frame)
    ctx.start_clock(call.skill.timeout_for(call.args, ctx.env))
    return call.skill.run(ctx, call.args)


def test_builtin_skills_are_namespaced_and_described(registry):
    names = registry.names
    for expected in (
        "nav.move",
        "nav.strafe",
        "nav.rotate",
        "nav.goto",
        "nav.stop",
        "nav.patrol",
        "body.stand",
        "body.sit",
        "body.lie_down",
        "body.sport",
        "sys.wait",
        "sys.status",
        "perception.describe",
    ):
        assert expected in names
    for skill in registry:
        assert skill.description and "." in skill.name


def test_tool_schemas_are_openai_functions(registry):
    tools = registry.tool_schemas()
    move = next(t for t in tools if t["function"]["name"] == "nav_move")
    params = move["function"]["parameters"]
    assert params["required"] == ["distance"]
    assert params["additionalProperties"] is False
    assert params["properties"]["distance"]["maximum"] == 1000
    sport = next(t for t in tools if t["function"]["name"] == "body_sport")
    assert "backflip" in sport["function"]["parameters"]["properties"]["trick"]["enum"]


def test_numbers_as_strings_are_accepted(registry):
    call = registry.validate(SkillCall("nav.move", {"distance": "1.5"}))
    assert call.args.distance == 1.5
    assert registry.validate(SkillCall("nav_rotate", {"degrees": 90})).name == "nav.rotate"


# A valid call of every skill with numeric arguments; each argument is then varied alone.
VALID = {
    "nav.move": {"distance": 1},
    "nav.strafe": {"distance": 1},
    "nav.rotate": {"degrees": 9},
    "nav.goto": {"x": 1, "y": 1},
    "nav.face": {"x": 1, "y": 1},
    "nav.patrol": {},
    "nav.follow": {"target": "person"},
    "sys.wait": {"seconds": 1},
}


def numeric_arguments(registry):
    return [
        (skill, name, info)
        for skill in registry
        for name, info in skill.args_model.model_fields.items()
        if is_numeric(info)
    ]


def test_every_numeric_argument_reads_units_and_refuses_booleans(registry):
    found = numeric_arguments(registry)
    assert {s.name for s, _, _ in found} == set(VALID)
    assert len(found) >= 12
    for skill, name, info in found:
        for flag in (True, False):  # pydantic alone would read True as 1 metre
            with pytest.raises(SkillValidationError, match=rf"'{name}': {flag} is a boolean"):
                registry.validate(SkillCall(skill.name, {**VALID[skill.name], name: flag}))
        kind = argument_kind(info)
        if kind is None:
            continue
        call = registry.validate(SkillCall(skill.name, {**VALID[skill.name], name: kind.example}))
        assert getattr(call.args, name) == units.read(kind.example, kind), (skill.name, name)
        other = next(k for k in units.KINDS if k is not kind)
        with pytest.raises(SkillValidationError, match=f"not an? {kind.name}"):
            registry.validate(SkillCall(skill.name, {**VALID[skill.name], name: f"1 {other.unit}"}))


def test_numbers_with_units_are_read_for_every_caller(registry):
    move = registry.validate(SkillCall("nav.move", {"distance": "3cm", "speed": "20 cm/s"}))
    assert (move.args.distance, move.args.speed) == (0.03, 0.2)
    assert move.args_dict() == {"distance": 0.03, "speed": 0.2}
    turn = registry.validate(SkillCall("nav.rotate", {"degrees": "1/4 turn"}))
    assert turn.args.degrees == 90.0
    goto = registry.validate(
        SkillCall("nav.goto", {"x": "6 in", "y": "-2 ft", "heading_degrees": "90°"})
    )
    assert (goto.args.x, goto.args.y, goto.args.heading_degrees) == (0.1524, -0.6096, 90.0)
    assert registry.validate(SkillCall("sys.wait", {"seconds": "500ms"})).args.seconds == 0.5
    assert registry.validate(SkillCall("nav.patrol", {"laps": "2"})).args.laps == 2


def test_a_numeric_argument_must_be_declared_with_its_kind():
    with pytest.raises(TypeError, match="Plain.distance: declare a numeric skill argument"):

        class Plain(SkillArgs):
            distance: float

    with pytest.raises(TypeError, match="MaybeCount.n: declare"):

        class MaybeCount(SkillArgs):
            n: int | None = None

    class Typed(SkillArgs):
        distance: Length
        n: Count = 1

    assert Typed(distance="30cm").distance == 0.3


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (SkillCall("nav.fly", {}), "unknown skill 'nav.fly'; available skills: nav.move"),
        (SkillCall("nav.move", {}), "missing required argument 'distance'"),
        (SkillCall("nav.move", {"distance": "far"}), "'distance': 'far' is not a length"),
        (SkillCall("nav.move", {"distance": "3 cmx"}), "'distance': '3 cmx': unknown unit 'cmx'"),
        (SkillCall("nav.move", {"distance": "3 s"}), "'3 s' is a duration, not a length"),
        (SkillCall("nav.move", {"distance": "2 km"}), "(got '2 km' = 2000.0)"),
        (SkillCall("nav.move", {"distance": True}), "'distance': True is a boolean"),
        (SkillCall("nav.patrol", {"laps": True}), "'laps': True is a boolean, not a count"),
        (SkillCall("nav.patrol", {"laps": "1.5"}), "'laps': '1.5' is not a count"),
        (SkillCall("nav.move", {"distance": 1, "turbo": True}), "unknown argument 'turbo'"),
        (SkillCall("nav.move", {"distance": float("nan")}), "finite number"),
        (SkillCall("nav.move", {"distance": 5000}), "less than or equal to 1000"),
        (SkillCall("nav.rotate", {"degrees": 90, "speed": -1}), "greater than 0"),
        (SkillCall("nav.goto", {"x": 1}), "give both x and y"),
        (SkillCall("nav.goto", {}), "give a target"),
        (SkillCall("body.sport", {"trick": "fly"}), "'trick' input should be"),
        (SkillCall("sys.wait", {"seconds": -1}), "greater than or equal to 0"),
        (SkillCall("nav.move", [1]), "arguments must be an object"),
        (SkillCall("", {}), "needs a skill name"),
    ],
)
def test_validation_errors_say_what_is_wrong(registry, call, message):
    with pytest.raises(SkillValidationError) as info:
        registry.validate(call)
    assert message in str(info.value)


def test_move_is_closed_loop_on_measured_pose(registry, robot):
    out = run(registry, robot, "nav.move", distance=1.0)
    assert robot.get_state().x == pytest.approx(1.0, abs=0.002)
    assert "moved 1.00 m forward" in out
    run(registry, robot, "nav.move", distance=-0.5)
    assert robot.get_state().x == pytest.approx(0.5, abs=0.003)


def test_rotate_is_precise_and_unwrapped(registry, robot):
    run(registry, robot, "nav.rotate", degrees=90)
    assert round(robot.get_state().yaw, 4) == 1.5708
    run(registry, robot, "nav.rotate", degrees=-450)
    assert math.degrees(robot.get_state().yaw) == pytest.approx(0.0, abs=0.05)
    assert robot.get_state().angle_turned == pytest.approx(math.radians(540), abs=0.01)


def test_strafe_goes_left_without_turning(registry, robot):
    run(registry, robot, "nav.strafe", distance=1.0)
    st = robot.get_state()
    assert (st.x, st.yaw) == (pytest.approx(0, abs=0.002), pytest.approx(0, abs=0.001))
    assert st.y == pytest.approx(1.0, abs=0.002)


def test_goto_point_and_place(registry, robot):
    run(registry, robot, "nav.goto", x=2.0, y=1.0)
    st = robot.get_state()
    assert (st.x, st.y) == (pytest.approx(2.0, abs=0.003), pytest.approx(1.0, abs=0.003))
    run(registry, robot, "nav.goto", place="kitchen", heading_degrees=180)  # round the box
    st = robot.get_state()
    assert (st.x, st.y) == (pytest.approx(4.0, abs=0.003), pytest.approx(2.5, abs=0.003))
    assert abs(math.degrees(st.yaw)) == pytest.approx(180, abs=0.1)


def test_motion_stands_up_first(registry, robot):
    run(registry, robot, "body.sit")
    run(registry, robot, "nav.move", distance=0.5)
    assert robot.get_state().x == pytest.approx(0.5, abs=0.003)


def test_motion_fails_when_auto_stand_is_off(registry, robot):
    settings = ShadowHoundConfig(motion={"auto_stand": False})
    run(registry, robot, "body.lie_down", settings)
    with pytest.raises(SkillError, match="stand up first"):
        run(registry, robot, "nav.move", settings, distance=0.5)


def test_stall_is_detected(registry, robot):
    robot.send_velocity = lambda vx, vy, wz: None  # a robot that ignores velocity
    with pytest.raises(SkillError, match="no progress"):
        run(registry, robot, "nav.move", distance=1.0)


def test_cancel_stops_a_move(registry, robot):
    call = registry.validate(SkillCall("nav.move", {"distance": 3.0}))
    cancelled = threading.Event()
    ctx = SkillContext(
        robot,
        PlanEnv(ShadowHoundConfig()),
        cancelled,
        on_progress=lambda f: cancelled.set() if f > 0.3 else None,
    )
    ctx.start_clock(60)
    with pytest.raises(MissionCancelled):
        call.skill.run(ctx, call.args)
    assert 0.5 < robot.get_state().x < 2.0


def test_timeout_on_robot_clock(registry, robot):
    call = registry.validate(SkillCall("sys.wait", {"seconds": 10}))
    ctx = SkillContext(robot, PlanEnv(ShadowHoundConfig()), threading.Event())
    ctx.start_clock(2.0)
    with pytest.raises(SkillTimeout, match="timed out after 2.0 s"):
        call.skill.run(ctx, call.args)


def test_wait_takes_robot_time(registry, robot):
    t0 = robot.now()
    run(registry, robot, "sys.wait", seconds=2.5)
    assert robot.now() - t0 == pytest.approx(2.5, abs=1e-6)


def test_describe_without_vision_model_is_honest(registry, robot):
    out = run(registry, robot, "perception.describe")
    assert out.startswith("In view: red ball about 3.0 m ahead")
    assert "A vision model (llm.vision) would describe the image itself" in out


def test_look_around_turns_full_circle(registry, robot):
    out = run(registry, robot, "perception.look_around")
    assert len(out.splitlines()) == 5 and out.count("vision model") == 1
    assert robot.get_state().angle_turned == pytest.approx(2 * math.pi, abs=0.01)


def test_status_reports_pose_and_battery(registry, robot):
    out = run(registry, robot, "sys.status")
    assert "Standing at x=0.00 m" in out and "battery 100.0%" in out


def test_unknown_place_is_a_plan_problem_without_a_map(registry):
    from shadowhound.config import SimConfig
    from shadowhound.robot.sim.robot import SimRobot

    robot = SimRobot(SimConfig(collisions=False), time_scale=0.0)  # no map: nothing to search
    with pytest.raises(
        ValueError, match="'garage' is not a place or an object I know. Places: kitchen"
    ):
        run(registry, robot, "nav.goto", place="garage")
    assert not robot.received_motion


def test_with_a_map_an_unknown_name_is_searched_for_and_the_failure_says_where(registry, robot):
    with pytest.raises(
        SkillError,
        match=r"did not find the garage: looked around from "
        r"\(0\.0, 0\.0\), \(",
    ):
        run(registry, robot, "nav.goto", place="garage")
