import math
import threading
import time

import pytest

from shadowhound import (
    MissionExecutor,
    MissionExecutorConfig,
    MissionStatus,
    MockRobot,
    Plan,
    PlanningError,
    RobotAgent,
    RobotAgentConfig,
    SimRobot,
    SkillCall,
    StepStatus,
    Usage,
)
from shadowhound.errors import RobotError

SAFETY = 60.0  # seconds: bounds a hung test (a loaded machine is slow), never what is asserted
# A walk slow enough (20 s of real time) that a press always lands while the robot walks.
SLOW_WALK = "walk forward 2 meters at 0.1 m/s"


def until(check, what: str) -> None:
    deadline = time.monotonic() + SAFETY
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


def test_documented_usage_of_the_original_names():
    executor = MissionExecutor(MissionExecutorConfig(robot=SimRobot()))
    result = executor.execute_mission("rotate 90 degrees")
    assert result.success and round(result.robot.yaw, 4) == 1.5708
    response, timing = executor.execute_mission("stand up")
    assert isinstance(response, str) and response
    assert set(timing) >= {
        "agent_duration",
        "total_duration",
        "overhead_duration",
        "agent_percentage",
    }
    assert MockRobot is SimRobot


def test_mission_result_carries_steps_timing_and_state(agent):
    result = agent.execute_mission("walk forward 1 meter then turn left 90 degrees")
    assert result.success and result.status is MissionStatus.SUCCEEDED
    assert [s.skill for s in result.steps] == ["nav.move", "nav.rotate"]
    assert all(s.status is StepStatus.SUCCEEDED for s in result.steps)
    assert result.steps[0].args == {"distance": 1.0}
    assert result.steps[0].robot_duration > 2.0  # 1 m at 0.4 m/s on the robot's clock
    assert result.robot.x == pytest.approx(1.0, abs=0.003)
    t = result.timing
    assert t.total_duration >= t.agent_duration + t.execution_duration
    assert 0 <= t.agent_percentage <= 100
    assert result.usage.total_tokens == 0 and result.usage.round_trips == 0
    assert "Done:" in result.response and "moved 1.00 m forward" in result.response


def test_events_in_order(agent):
    seen = []
    agent.add_listener(lambda e: seen.append((e.kind, e.data.get("step", {}).get("index"))))
    agent.execute_mission("sit down and then stand up")
    assert seen == [
        ("mission_started", None),
        ("plan_ready", None),
        ("step_started", 1),
        ("step_finished", 1),
        ("step_started", 2),
        ("step_finished", 2),
        ("mission_finished", None),
    ]


def test_a_broken_listener_does_not_break_the_mission(agent):
    agent.add_listener(lambda e: 1 / 0)
    assert agent.execute_mission("stand up").success


def test_unsubscribe(agent):
    seen = []
    unsubscribe = agent.add_listener(seen.append)
    unsubscribe()
    agent.execute_mission("stand up")
    assert seen == []


@pytest.mark.parametrize(
    "text",
    [
        "",
        "   ",
        "blorp the zanzibar",
        "x" * 5000,
        None,
        42,
        "walk forward 500 meters",
        "do a backflip",
    ],
)
def test_bad_missions_fail_clearly_and_never_move(agent, robot, text):
    result = agent.execute_mission(text)
    assert not result.success
    assert result.response and len(result.response) < 2000
    assert not robot.received_motion
    assert agent.get_diagnostics()["status"] == "failed" or text is None or text == 42


def test_refusal_lists_every_problem(agent, robot):
    result = agent.run_plan(
        [
            SkillCall("nav.move", {"distance": 50}),
            SkillCall("body.sport", {"trick": "backflip"}),
            SkillCall("nav.fly", {}),
        ]
    )
    assert not result.success
    assert {r.split(":")[0] for r in result.refusals} == {
        "step 1 (nav.move)",
        "step 2 (body.sport)",
        "step 3",
    }
    assert any("per step" in r for r in result.refusals)
    assert any("geofence" in r for r in result.refusals)
    assert "Refused before moving" in result.response
    assert all(s.status is StepStatus.SKIPPED for s in result.steps)
    assert not robot.received_motion


def test_a_failed_step_stops_the_mission_and_the_robot(agent, robot):
    robot.send_velocity = lambda *a: None  # motors dead: moves stall
    result = agent.run_plan(
        [SkillCall("body.sit"), SkillCall("nav.move", {"distance": 1}), SkillCall("body.sit")]
    )
    assert not result.success and result.status is MissionStatus.FAILED
    assert [s.status for s in result.steps] == [
        StepStatus.SUCCEEDED,
        StepStatus.FAILED,
        StepStatus.SKIPPED,
    ]
    assert "no progress" in result.response and "The robot is stopped" in result.response
    assert robot.commands[-1].kind == "stop"


class _RefusingStop(SimRobot):
    """A robot whose hard stop takes effect but whose driver then reports an error."""

    def emergency_stop(self) -> None:
        super().emergency_stop()
        raise RobotError("the driver did not acknowledge the stop")


def test_estop_cancels_the_mission_even_when_the_robots_stop_raises() -> None:
    robot = _RefusingStop(time_scale=1.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    box: dict = {}
    worker = threading.Thread(target=lambda: box.update(r=agent.execute_mission(SLOW_WALK)))
    worker.start()
    until(lambda: robot.get_state().vx > 0.05, "the robot to walk")
    with pytest.raises(RobotError, match="did not acknowledge"):
        agent.estop()  # the caller hears of the error ...
    worker.join(SAFETY)
    assert not worker.is_alive()  # ... and the mission ended all the same, latched
    assert agent.estop_latched and robot.get_state().vx == 0.0
    assert box["r"].status is MissionStatus.STOPPED and "e-stop" in box["r"].response


def test_estop_while_a_mission_runs_in_another_thread():
    robot = SimRobot(time_scale=1.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    box = {}
    worker = threading.Thread(target=lambda: box.update(r=agent.execute_mission(SLOW_WALK)))
    worker.start()
    diagnosed = []

    def walking() -> bool:
        diagnosed.append(agent.get_diagnostics())  # diagnostics work while the mission runs
        return robot.get_state().vx > 0.05

    until(walking, "the robot to walk")
    diag = diagnosed[-1]
    assert diag["status"] == "executing" and diag["current_skill"] == "nav.move"
    agent.estop()
    assert robot.get_state().vx == 0.0  # hard stop at once
    worker.join(SAFETY)
    result = box["r"]
    assert result.status is MissionStatus.STOPPED and "e-stop" in result.response
    x = robot.get_state().x
    assert x < 2.0
    refused = agent.execute_mission("walk forward 1 meter")
    assert not refused.success and "e-stop is latched" in refused.response
    agent.release_estop()
    assert agent.execute_mission("stand up").success


def test_cancel_stops_the_mission(agent, robot):
    agent.add_listener(
        lambda e: (
            agent.cancel() if e.kind == "step_started" and e.data["step"]["index"] == 2 else None
        )
    )
    result = agent.execute_mission("turn left 90 degrees then walk forward 2 meters")
    assert result.status is MissionStatus.STOPPED
    assert result.steps[1].status is StepStatus.CANCELLED
    assert robot.get_state().x < 0.05


def test_one_mission_at_a_time():
    robot = SimRobot(time_scale=1.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    box = {}
    worker = threading.Thread(target=lambda: box.update(r=agent.execute_mission("wait 60 seconds")))
    worker.start()
    until(lambda: agent.get_diagnostics()["status"] == "executing", "the wait to run")
    busy = agent.execute_mission("stand up")
    assert not busy.success and "another mission is running" in busy.response
    agent.cancel()
    worker.join(SAFETY)
    assert not worker.is_alive() and box["r"].status is MissionStatus.STOPPED


def test_planner_failure_and_usage_are_reported(robot):
    class Broken:
        name = kind = "broken"
        needs_context = True

        def plan(self, text, context=None):
            raise PlanningError("model said nonsense", usage=Usage(100, 20, 1))

    agent = RobotAgent(RobotAgentConfig(robot=robot, planner=Broken()))
    result = agent.execute_mission("walk")
    assert not result.success and result.response == "model said nonsense"
    assert result.usage.prompt_tokens == 100 and result.usage.round_trips == 1


def test_garbage_plans_from_a_planner_never_move(robot):
    class Garbage:
        name = kind = "garbage"
        needs_context = True

        def plan(self, text, context=None):
            return Plan(
                [
                    SkillCall("nav.move", {"distance": "1e9"}),
                    SkillCall("nav.rotate", {"degrees": "ninety"}),
                    SkillCall(None, None),
                    SkillCall("nav.move", "forward"),
                ]
            )

    agent = RobotAgent(RobotAgentConfig(robot=robot, planner=Garbage()))
    result = agent.execute_mission("anything")
    assert not result.success and len(result.refusals) == 4
    assert not robot.received_motion


def test_too_many_steps_are_refused(agent, robot):
    result = agent.run_plan([SkillCall("body.stand")] * 51)
    assert not result.success and "at most 50" in result.response


def test_diagnostics_shape(agent):
    agent.execute_mission("walk forward 1 meter")
    d = agent.get_diagnostics()
    assert d["status"] == "succeeded" and d["progress"] == 1.0
    assert d["robot"]["x"] == pytest.approx(1.0, abs=0.003)
    assert d["last_mission"].startswith("succeeded: 'walk forward 1 meter'")
    assert d["backend"] == "offline" and d["limits"]["max_linear_speed"] == 0.5


def test_chat_answers_without_moving(agent, robot):
    agent.execute_mission("walk forward 1 meter")
    assert "x=1.00 m" in agent.chat("where are you?")
    assert "%" in agent.chat("how is your battery")
    assert "walk forward 1 meter" in agent.chat("what did you do last?")
    assert '"move forward 1 m"' in agent.chat("what can you do?")
    assert "red ball" in agent.chat("what do you see?")
    before = robot.counters["motion_commands"]
    reply = agent.chat("walk forward 2 meters")
    assert "sounds like a mission" in reply
    assert robot.counters["motion_commands"] == before
    assert agent.chat("")


def test_camera_frame_from_interface_is_used(agent):
    from tests.images import tiny_jpeg

    agent.update_camera_image(tiny_jpeg(64, 48))
    result = agent.execute_mission("what do you see?")
    assert result.success and "64x48 JPEG frame" in result.response
    with pytest.raises(ValueError, match="JPEG or PNG"):
        agent.update_camera_image(b"not an image")


def test_robot_status_and_skills(agent):
    status = agent.get_robot_status()
    assert set(status) >= {
        "x",
        "y",
        "yaw",
        "posture",
        "battery",
        "distance_travelled",
        "angle_turned",
    }
    assert {s["name"] for s in agent.get_available_skills()} >= {"nav.move", "body.sport"}


def test_square_returns_to_start(agent):
    result = agent.execute_mission("walk in a square with 1.5 meter sides")
    st = result.robot
    assert result.success and math.hypot(st.x, st.y) < 0.01
    assert st.distance_travelled == pytest.approx(6.0, abs=0.02)


def test_a_square_through_the_blue_box_is_refused_naming_it(agent, robot):
    """Relative moves stay straight lines: a leg the map shows would hit something is refused
    before anything moves, saying what and where (the 2 m square's second side ends 0.5 m from
    the blue box at (2.5, 2))."""
    result = agent.execute_mission("walk in a square with 2 meter sides")
    assert not result.success and not robot.received_motion
    assert "step 3 (nav.move): nav.move 2 m: the blue box is in the way at 1." in result.response


def test_dry_run_predicts_without_moving(agent, robot):
    result = agent.dry_run("walk forward 2 meters, turn left and walk 1 meter")
    assert result.success and result.dry_run
    end = result.predicted_path[-1]
    assert (end.x, end.y) == (pytest.approx(2.0), pytest.approx(1.0))
    assert [s.skill for s in result.steps] == ["nav.move", "nav.rotate", "nav.move"]
    assert not robot.received_motion and robot.commands == []
    refused = agent.dry_run("walk forward 4 meters three times")
    assert not refused.success and "geofence" in refused.response
    assert not agent.dry_run("blorp").success


def test_interfaces_may_name_missions(agent):
    assert agent.execute_mission("stand up", mission_id="web-1").mission_id == "web-1"
    assert agent.dry_run("sit down", mission_id="web_2").mission_id == "web_2"
    with pytest.raises(ValueError, match="a mission id must be 1 to 64"):
        agent.execute_mission("stand up", mission_id="no spaces allowed")


def test_a_robot_that_cannot_report_its_state_is_refused_clearly(agent, robot):
    from shadowhound import RobotError

    def no_odometry():
        raise RobotError("no odometry on /odom for 0.8 s")

    robot.get_state = no_odometry
    result = agent.execute_mission("walk forward 1 meter")
    assert not result.success and result.robot is None
    assert "the robot cannot report its state: no odometry" in result.response
    assert not robot.received_motion
    assert agent.get_diagnostics()["robot"] == {
        "connected": False,
        "error": "no odometry on /odom for 0.8 s",
    }


def test_explicit_plans_read_units_like_every_other_path(agent, robot):
    result = agent.run_plan(
        [SkillCall("nav.move", {"distance": "3cm"}), SkillCall("nav.rotate", {"degrees": "90°"})]
    )
    assert result.success, result.response
    assert result.steps[0].args == {"distance": 0.03}
    st = robot.get_state()
    assert st.x == pytest.approx(0.03, abs=0.003)
    assert math.degrees(st.yaw) == pytest.approx(90, abs=0.1)


@pytest.mark.parametrize("distance", [True, "3 seconds", "3 cmx"])
def test_explicit_plans_with_unreadable_quantities_never_move(agent, robot, distance):
    result = agent.run_plan([SkillCall("nav.move", {"distance": distance})])
    assert not result.success and "'distance'" in result.response
    assert "give a number of metres" in result.response
    assert not robot.received_motion
