"""The ROS node's pure-Python parts: parameters, conversions, the mission worker, DDS env.

No rclpy needed: these run on every interpreter, also where ROS 2 is not installed.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
from xml.etree import ElementTree

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.ros import convert
from shadowhound.ros.dds import LOOPBACK_PROFILE, loopback_env, session_domain_id
from shadowhound.ros.params import NodeSettings, ParameterError, parse_parameters
from shadowhound.worker import JobListener, MissionJob, MissionWorker

# -- parameters --------------------------------------------------------------------------


def test_defaults_match_the_original_node() -> None:
    s = parse_parameters({})
    assert s == NodeSettings()
    assert (s.mission_topic, s.status_topic, s.diagnostics_topic) == (
        "mission_command",
        "mission_status",
        "/shadowhound/diagnostics",
    )
    assert s.web_interface_port == 8080 and s.time_scale == 1.0 and not s.camera_compressed


def test_camera_type_auto_follows_the_topic_name() -> None:
    assert parse_parameters({"camera_topic": "/camera/compressed"}).camera_compressed
    assert not parse_parameters(
        {"camera_topic": "/camera/compressed", "camera_type": "raw"}
    ).camera_compressed
    assert parse_parameters({"camera_type": "compressed"}).camera_compressed


def test_integers_are_accepted_for_time_scale() -> None:
    assert parse_parameters({"time_scale": 0}).time_scale == 0.0


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"web_interface_port": 0}, "web_interface_port must be in 1..65535, got 0"),
        ({"web_interface_port": True}, "web_interface_port must be an integer, got bool True"),
        ({"enable_web_ui": "yes"}, "enable_web_ui must be true or false, got str 'yes'"),
        ({"time_scale": -1.0}, "time_scale must be a number in 0..100"),
        ({"time_scale": float("nan")}, "time_scale must be a number in 0..100"),
        ({"robot": "spot"}, "robot must be sim or go2, got 'spot'"),
        ({"odom_timeout": 0.0}, "odom_timeout must be a number of seconds in 0.05..10, got 0.0"),
        ({"robot_namespace": "robot 0"}, "robot_namespace 'robot 0' is not a valid ROS namespace"),
        ({"cmd_vel_topic": "cmd vel"}, "cmd_vel_topic 'cmd vel' is not a valid ROS topic name"),
        ({"camera_type": "h264"}, "camera_type must be one of auto, raw, compressed"),
        ({"status_topic": ""}, "status_topic '' is not a valid ROS topic name"),
        ({"backend_config": " "}, "backend_config must name a profile or a YAML file"),
        (
            {"navigation": "nav3"},
            "navigation must be one of auto, nav2, direct (or '' for the profile's), got 'nav3'",
        ),
        ({"map_topic": "my map"}, "map_topic 'my map' is not a valid ROS topic name"),
    ],
)
def test_invalid_parameters_are_explained(values: dict, message: str) -> None:
    with pytest.raises(ParameterError, match="invalid ROS parameters") as info:
        parse_parameters(values)
    assert message in str(info.value)


def test_every_problem_is_reported_at_once() -> None:
    with pytest.raises(ParameterError) as info:
        parse_parameters({"web_interface_port": 99999, "robot": "spot", "time_scale": "x"})
    message = str(info.value)
    assert message.count(";") == 2
    for part in (
        "web_interface_port must be in 1..65535",
        "robot must be sim or go2",
        "time_scale must be a number, got str 'x'",
    ):
        assert part in message


def test_agent_settings_take_the_profile_then_the_parameters() -> None:
    settings = parse_parameters({"backend_config": "offline", "time_scale": 0.5})
    config = settings.agent_settings()
    assert (
        config.backend == "offline" and config.sim.time_scale == 0.5 and config.robot.type == "sim"
    )
    with pytest.raises(Exception, match="unknown config profile 'nope'"):
        parse_parameters({"backend_config": "nope"}).agent_settings()


def test_navigation_comes_from_the_profile_unless_the_parameter_sets_it() -> None:
    assert parse_parameters({}).agent_settings().navigation == "auto"
    assert parse_parameters({"navigation": "nav2"}).agent_settings().navigation == "nav2"
    go2 = parse_parameters({"robot": "go2", "map_topic": "", "nav2_action": ""}).go2_options()
    assert (go2["map_topic"], go2["scan_topic"], go2["nav2_action"]) == ("", "scan", "")


def test_the_speech_topic_is_go2_ros2_sdks_tts_unless_set_and_empty_turns_the_voice_off() -> None:
    assert parse_parameters({"robot": "go2"}).go2_options()["speech_topic"] == "/tts"
    assert parse_parameters({"speech_topic": ""}).go2_options()["speech_topic"] == ""
    assert parse_parameters({"speech_topic": "robot0/tts"}).speech_topic == "robot0/tts"
    with pytest.raises(ParameterError, match="speech_topic '1tts' is not a valid ROS topic"):
        parse_parameters({"speech_topic": "1tts"})


# -- conversions ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("diagnostics", "level"),
    [
        ({"status": "idle"}, convert.OK),
        ({"status": "executing"}, convert.OK),
        ({"status": "succeeded"}, convert.OK),
        ({"status": "failed"}, convert.WARN),
        ({"status": "stopped"}, convert.WARN),
        ({"status": "idle", "estop": True}, convert.ERROR),
    ],
)
def test_diagnostic_level_follows_the_agent_status(diagnostics: dict, level: int) -> None:
    assert convert.diagnostic_level(diagnostics) == level


def test_an_unknown_battery_warns_in_diagnostics_and_is_never_a_number() -> None:
    from shadowhound.state import RobotState

    robot = RobotState(battery=None).to_dict()
    assert robot["battery"] is None
    diagnostics = {"status": "idle", "robot": robot}
    assert convert.diagnostic_level(diagnostics) == convert.WARN
    assert (
        convert.diagnostic_message(diagnostics) == "idle; battery level unknown (no battery source)"
    )
    assert dict(convert.diagnostic_values(diagnostics))["battery"] == "unknown"
    assert convert.diagnostic_level({"status": "failed", "robot": robot}) == convert.WARN
    known = {"status": "idle", "robot": RobotState(battery=42.0).to_dict()}
    assert convert.diagnostic_level(known) == convert.OK
    assert dict(convert.diagnostic_values(known))["battery"] == "42.0"


def test_diagnostic_values_are_strings_with_the_documented_keys() -> None:
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0)))
    values = dict(convert.diagnostic_values(agent.get_diagnostics(), {"robot": "sim-go2"}))
    assert all(isinstance(v, str) for v in values.values())
    assert values["status"] == "idle" and values["estop"] == "false"
    assert float(values["battery"]) == pytest.approx(100.0)
    assert {
        "current_skill",
        "progress",
        "errors",
        "backend",
        "pose_x",
        "pose_y",
        "pose_yaw",
        "robot",
    } <= set(values)
    assert values["memory_recall"] == "off" and values["memory_problem"] == ""
    broken = {"memory": {"recall": "unavailable", "recall_problem": "the store 'x' is corrupt"}}
    values = dict(convert.diagnostic_values(broken))
    assert values["memory_recall"] == "unavailable" and "corrupt" in values["memory_problem"]
    assert convert.diagnostic_message({"status": "failed", "errors": ["a", "b"]}) == "failed: b"


def test_robot_status_is_strict_json_when_odometry_lies() -> None:
    """One NaN in the pose made robot_status a message no strict JSON reader takes."""
    from tests.lying_odometry import LyingOdometry
    from tests.strict_json import strict_loads

    robot = LyingOdometry(x=math.nan, yaw=math.inf)
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    text = convert.robot_status_json(agent.get_robot_status())
    status = strict_loads(text)
    assert isinstance(status, dict)
    assert status["x"] is None and status["yaw"] is None and status["yaw_deg"] is None
    assert status["y"] == 0.0 and status["posture"] == "standing"
    values = dict(convert.diagnostic_values(agent.get_diagnostics()))
    assert (values["pose_x"], values["pose_y"], values["pose_yaw"]) == ("unknown", "0.0", "unknown")


def test_shorten_keeps_status_lines_short() -> None:
    assert convert.shorten("a\nb") == "a b"
    assert len(convert.shorten("x" * 1000)) == 200


# -- the mission worker --------------------------------------------------------------------


class _Recorder:
    def __init__(self) -> None:
        self.started: list[str] = []
        self.finished: list[MissionJob] = []

    def start(self, job: MissionJob) -> None:
        self.started.append(job.command)

    def finish(self, job: MissionJob) -> None:
        self.finished.append(job)


def _listened(worker: MissionWorker, start: JobListener, finish: JobListener) -> MissionWorker:
    worker.on("started", start)
    worker.on("finished", finish)
    return worker


@pytest.fixture
def worker_agent() -> RobotAgent:
    agent = RobotAgent(
        RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=ShadowHoundConfig())
    )
    agent.initialize()
    return agent


def test_topic_missions_queue_and_run_in_order(worker_agent: RobotAgent) -> None:
    seen = _Recorder()
    worker = _listened(MissionWorker(worker_agent), seen.start, seen.finish)
    jobs = [MissionJob(c) for c in ("turn left 10 degrees", "", "turn right 10 degrees")]
    assert all(worker.submit(j) is None for j in jobs)
    for job in jobs:
        assert job.done.wait(10)
    worker.stop()
    assert seen.started == [j.command for j in jobs]
    assert [j.result.success for j in jobs] == [True, False, True]


def test_action_jobs_start_only_when_idle_and_the_estop_drops_waiting_ones(
    worker_agent: RobotAgent,
) -> None:
    gate = threading.Event()
    seen = _Recorder()

    def slow_start(job: MissionJob) -> None:
        seen.start(job)
        gate.wait(10)

    worker = _listened(MissionWorker(worker_agent, max_queue=1), slow_start, seen.finish)
    first, waiting = MissionJob("turn left 10 degrees"), MissionJob("turn left 20 degrees")
    assert worker.submit(first) is None and worker.submit(waiting) is None
    for _ in range(1000):  # until the worker holds the first job
        if seen.started:
            break
        threading.Event().wait(0.01)
    assert "already waiting" in (worker.submit(MissionJob("sit down")) or "")
    assert "another mission is running" in (worker.start_now(MissionJob("x")) or "")
    assert worker.drop_queued("e-stop") == [waiting]
    assert waiting.done.is_set() and waiting.dropped == "e-stop" and waiting.result is None
    gate.set()
    assert first.done.wait(10) and first.result is not None and first.result.success
    idle = MissionJob("walk forward 0.5 meters", source="action", dry_run=True)
    assert worker.start_now(idle) is None and idle.done.wait(10)
    assert idle.result is not None and idle.result.success
    assert not worker_agent.robot.get_state().distance_travelled  # the dry run never moved
    worker.stop()


def test_events_reach_only_the_running_job(worker_agent: RobotAgent) -> None:
    kinds: list[str] = []
    worker = MissionWorker(worker_agent)
    job = MissionJob("turn left 10 degrees", on_event=lambda e: kinds.append(e.kind))
    worker.submit(job)
    assert job.done.wait(10)
    worker_agent.estop()  # emitted from this thread, not part of the job
    worker.stop()
    assert kinds[0] == "mission_started" and kinds[-1] == "mission_finished"
    assert "estop" not in kinds


def test_a_job_cancelled_before_it_starts_never_runs(worker_agent: RobotAgent) -> None:
    worker = MissionWorker(worker_agent)
    job = MissionJob("turn left 10 degrees")
    job.cancelled.set()
    worker.submit(job)
    assert job.done.wait(10) and job.dropped == "cancelled before it started"
    worker.stop()


def test_a_cancel_between_pick_up_and_start_still_stops_the_mission(
    worker_agent: RobotAgent,
) -> None:
    def cancel_now(job: MissionJob) -> None:  # as if the cancel arrived right here
        job.cancelled.set()

    worker = MissionWorker(worker_agent)
    worker.on("started", cancel_now)
    job = MissionJob("walk forward 1 meter")
    worker.submit(job)
    assert job.done.wait(10) and job.result is not None
    worker.stop()
    assert job.result.status.value == "stopped" and not job.result.success
    assert not worker_agent.robot.get_state().distance_travelled


# -- DDS environment -----------------------------------------------------------------------


def test_loopback_environment_keeps_dds_on_this_machine() -> None:
    env = loopback_env(42)
    assert env["ROS_DOMAIN_ID"] == "42" and env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert env["FASTRTPS_DEFAULT_PROFILES_FILE"] == str(LOOPBACK_PROFILE)
    xml = ElementTree.parse(LOOPBACK_PROFILE).getroot().iter()
    tags = {e.tag.split("}")[1]: (e.text or "").strip() for e in xml}
    assert tags["useBuiltinTransports"] == "false" and tags["address"] == "127.0.0.1"
    assert 1 <= session_domain_id() <= 100


def test_each_test_process_holds_a_domain_of_its_own(tmp_path) -> None:
    from tests.ros.conftest import DOMAIN, claim_domain

    assert os.environ["ROS_DOMAIN_ID"] == str(DOMAIN)  # this process's, set before rclpy
    first, held = claim_domain(100, tmp_path)
    second, other = claim_domain(100, tmp_path)  # another worker or run starting at the same
    assert (first, second) == (100, 1)  # the next free one, wrapping after 100
    held.close()  # the first process ended
    third, again = claim_domain(100, tmp_path)
    assert third == 100
    other.close()
    again.close()


def test_importing_the_ros_package_does_not_import_rclpy() -> None:
    code = (
        "import sys, shadowhound, shadowhound.ros, shadowhound.ros.params, "
        "shadowhound.ros.convert; assert 'rclpy' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


def test_the_launch_file_declares_every_parameter_with_its_default() -> None:
    import ast
    from pathlib import Path

    from shadowhound.ros.params import PARAMETERS

    launch = Path(__file__).resolve().parents[2] / "ros2/shadowhound/launch/mission_node.launch.py"
    tree = ast.parse(launch.read_text(encoding="utf-8"))
    found = next(
        n.value
        for n in tree.body
        if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "ARGUMENTS"
    )
    arguments = ast.literal_eval(found)
    assert set(arguments) == set(PARAMETERS)
    for name, (default, _help) in PARAMETERS.items():
        assert (
            arguments[name] == str(default).lower()
            if isinstance(default, bool)
            else arguments[name] == str(default)
        ), name
