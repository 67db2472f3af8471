"""The `shadowhound` command as users run it: a real process, real stdout/stderr/exit codes."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"
SAFETY = 120  # seconds: bounds a hung process (a loaded machine starts Python slowly)


def shadowhound(*args, stdin=None, env=None):
    full_env = {**os.environ, **(env or {})}
    full_env.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        input=stdin,
        timeout=SAFETY,
        env=full_env,
    )


def test_run_json_prints_exactly_one_object():
    proc = shadowhound("run", "--json", "rotate 90 degrees")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)  # exactly one JSON document, nothing else on stdout
    assert out["success"] is True
    assert out["robot"]["yaw"] == 1.5708
    assert set(out["robot"]) >= {
        "x",
        "y",
        "yaw",
        "posture",
        "battery",
        "distance_travelled",
        "angle_turned",
    }
    assert out["steps"][0]["skill"] == "nav.rotate"
    assert set(out["timing"]) >= {
        "agent_duration",
        "total_duration",
        "overhead_duration",
        "agent_percentage",
    }
    assert out["usage"]["total_tokens"] == 0
    assert "nav.rotate" in proc.stderr  # progress goes to stderr


def test_run_human_output_and_failure_exit_code():
    proc = shadowhound("run", "stand up and walk forward 1.5 meters")
    assert proc.returncode == 0
    assert "Done:" in proc.stdout and "x=1.50" in proc.stdout
    proc = shadowhound("run", "--quiet", "blorp the zanzibar")
    assert proc.returncode == 1
    assert "not understand" in proc.stdout.lower() or "didn't understand" in proc.stdout.lower()
    assert proc.stderr == ""


def test_refused_mission_exits_1_with_reason():
    proc = shadowhound("run", "--json", "walk forward 500 meters")
    assert proc.returncode == 1
    out = json.loads(proc.stdout)
    assert out["success"] is False and out["robot"]["distance_travelled"] == 0
    assert "limit" in out["response"]


def test_usage_and_config_errors_exit_2(tmp_path):
    assert shadowhound("run").returncode == 2
    assert shadowhound().returncode == 2
    proc = shadowhound("--config", "nope", "run", "stand up")
    assert proc.returncode == 2 and "unknown config profile 'nope'" in proc.stderr
    bad = tmp_path / "bad.yaml"
    bad.write_text("safety: {max_linear_speed: fast}")
    proc = shadowhound("run", "--config", str(bad), "stand up")
    assert proc.returncode == 2 and "safety.max_linear_speed" in proc.stderr
    proc = shadowhound("run", "--backend", "openai", "stand up", env={"OPENAI_API_KEY": ""})
    assert proc.returncode == 2 and "set the environment variable OPENAI_API_KEY" in proc.stderr


def test_skills_listing_and_json():
    proc = shadowhound("skills")
    assert proc.returncode == 0 and "nav.move(distance, speed?)" in proc.stdout
    skills = json.loads(shadowhound("skills", "--json").stdout)
    move = next(s for s in skills if s["name"] == "nav.move")
    assert move["parameters"]["properties"]["distance"]["type"] == "number"


def test_chat_repl_from_stdin():
    proc = shadowhound(
        "chat", stdin="where are you?\n/run walk forward 1 meter\nwhere are you?\n/bogus\n/quit\n"
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert "x=0.00 m" in lines[0]
    assert lines[1].startswith("ok: Done: moved 1.00 m forward")
    assert "x=1.00 m" in lines[2]
    assert "unknown command '/bogus'" in lines[3]


def test_eval_public_cases_all_pass():
    proc = shadowhound("eval", str(DATA / "missions_public.yaml"))
    assert proc.returncode == 0, proc.stdout
    assert proc.stdout.strip().splitlines()[-1].endswith("cases passed (100.0%)")


def test_eval_json_and_failing_cases(tmp_path):
    cases = tmp_path / "cases.yaml"
    cases.write_text(
        '- mission: "walk forward 1 meter"\n  expect: {x: 2.0, moved: true}\n'
        '- mission: "sit down"\n  expect: {posture: sitting}\n'
    )
    proc = shadowhound("eval", "--json", str(cases))
    assert proc.returncode == 1
    report = json.loads(proc.stdout)
    assert (report["passed"], report["failed"]) == (1, 1)
    assert report["cases"][0]["failures"] == ["x: expected 2.0, got 1.0006"]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("mission: x", "must be a YAML list"),
        ("- {expect: {}}", "case 1"),
        ("- {mission: hi, expect: {z: 1}}", "unknown expect keys ['z']"),
        ("- {mission: hi, expect: {x: far}}", "expect.x must be a number"),
    ],
)
def test_eval_bad_case_file(tmp_path, content, message):
    cases = tmp_path / "cases.yaml"
    cases.write_text(content)
    proc = shadowhound("eval", str(cases))
    assert proc.returncode == 2 and message in proc.stderr


def test_config_command_shows_no_secrets():
    proc = shadowhound("config", env={"OPENAI_API_KEY": "sk-secret-123"})
    assert proc.returncode == 0 and "max_linear_speed: 0.5" in proc.stdout
    assert "sk-secret-123" not in proc.stdout


def test_run_dry_run_shows_plan_and_path_without_moving():
    proc = shadowhound("run", "--dry-run", "walk forward 1 meter then come back")
    assert proc.returncode == 0
    assert "[1] nav.move(distance=1.0)" in proc.stdout
    assert (
        "predicted path (2.00 m, 3 waypoints): (0.00, 0.00) -> (1.00, 0.00) -> (0.00, 0.00)"
        in proc.stdout
    )
    assert "nothing moved" in proc.stdout
    out = json.loads(shadowhound("run", "--dry-run", "--json", "walk forward 9 meters").stdout)
    assert out["dry_run"] and not out["success"] and out["robot"]["distance_travelled"] == 0


def test_dry_run_shows_the_path_around_the_red_ball_and_what_refuses_a_straight_leg():
    """The default scene: the red ball stands at (3, 0)."""
    around = shadowhound("run", "--dry-run", "go to x=4, y=0")
    assert around.returncode == 0, around.stdout
    line = next(x for x in around.stdout.splitlines() if x.startswith("predicted path ("))
    length, corners = float(line.split("(")[1].split(" m")[0]), line.split(": ", 1)[1]
    assert 4.0 < length < 4.0 * 1.15 and corners.count("->") >= 2  # a detour, not a line
    assert corners.startswith("(0.00, 0.00)") and corners.endswith("(4.00, 0.00)")
    straight = shadowhound("run", "--dry-run", "go forward 4 meters")
    assert straight.returncode == 1
    assert "nav.move 4 m: the red ball is in the way at 2.4 m" in straight.stdout


def test_risky_trick_needs_approval_on_the_command_line():
    refused = shadowhound("run", "-q", "do a backflip")  # no terminal: nobody to ask
    assert refused.returncode == 1 and "no interface that can ask a person" in refused.stdout
    approved = shadowhound("run", "-q", "--yes", "do a backflip")
    assert approved.returncode == 0 and "performed backflip" in approved.stdout


# -- run --json answers with one JSON object on every exit -------------------------------------


def one_error_object(proc, code, kind):
    """stdout is exactly one JSON object saying what went wrong, and the exit code is kept."""
    assert proc.returncode == code, proc.stderr
    answer = json.loads(proc.stdout)  # raises on nothing, or on more than one document
    assert answer["success"] is False and answer["status"] == "error"
    assert answer["error_kind"] == kind and answer["exit_code"] == code
    assert answer["error"] and answer["error"] in answer["response"]
    assert answer["error"] in proc.stderr  # people see it too
    assert "Traceback" not in proc.stderr
    return answer


def closed_port():
    """A loopback port nothing listens on (bound, then closed)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def test_run_json_unreachable_backend_is_one_json_error(tmp_path):
    url = f"http://127.0.0.1:{closed_port()}/v1"
    proc = shadowhound(
        "run",
        "--json",
        "--backend",
        "llamacpp",
        "--base-url",
        url,
        "--model",
        "m",
        "stand up",
        env={"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path)},
    )
    answer = one_error_object(proc, 2, "backend_unavailable")
    assert url in answer["error"] and answer["mission"] == "stand up"


def test_run_json_corrupt_history_database_is_one_json_error(tmp_path):
    (tmp_path / "history.db").write_bytes(b"this is not a database" * 100)
    proc = shadowhound(
        "run", "--json", "stand up", env={"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path)}
    )
    answer = one_error_object(proc, 2, "configuration")
    assert "history.db" in answer["error"] and "corrupt" in answer["response"]


@pytest.mark.parametrize(
    "args",
    [
        ("--config", "nope", "run", "--json", "stand up"),
        ("run", "--json", "--config", "nope", "stand up"),
        ("run", "--json", "--config", "BAD", "stand up"),
    ],
)
def test_run_json_bad_profile_is_one_json_error(tmp_path, args):
    bad = tmp_path / "bad.yaml"
    bad.write_text("safety: {max_linear_speed: fast}")
    proc = shadowhound(*(str(bad) if a == "BAD" else a for a in args))
    answer = one_error_object(proc, 2, "configuration")
    assert "nope" in answer["response"] or "safety.max_linear_speed" in answer["response"]


@pytest.mark.parametrize(
    "args",
    [
        ("run", "--json"),  # no mission
        ("run", "--json", "--backend", "skynet", "stand up"),
        ("--time-scale", "slow", "run", "--json", "stand up"),
    ],
)
def test_run_json_usage_errors_are_one_json_error(args):
    proc = shadowhound(*args)
    one_error_object(proc, 2, "usage")
    assert proc.stderr.startswith("usage: shadowhound")


def test_run_json_results_carry_the_exit_code():
    proc = shadowhound("run", "--json", "walk forward 500 meters")
    answer = json.loads(proc.stdout)
    assert proc.returncode == answer["exit_code"] == 1 and answer["status"] == "failed"
    assert answer["error"]
    proc = shadowhound("run", "--json", "stand up")
    answer = json.loads(proc.stdout)
    assert proc.returncode == answer["exit_code"] == 0 and answer["error"] is None


def start_json_run(*args, env=None):
    full_env = {**os.environ, **(env or {})}
    full_env.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.Popen(
        [sys.executable, "-m", "shadowhound", "run", "--json", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=full_env,
    )


def interrupt(proc):
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=SAFETY)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def test_run_json_interrupted_while_connecting_is_one_json_error(tmp_path):
    """Ctrl-C while the backend check waits on a server that accepts and never answers."""
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        url = f"http://127.0.0.1:{listener.getsockname()[1]}/v1"
        proc = start_json_run(
            "--backend",
            "llamacpp",
            "--base-url",
            url,
            "--model",
            "m",
            "stand up",
            env={"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path)},
        )
        listener.settimeout(SAFETY)
        conn, _ = listener.accept()  # the check is now waiting for an answer
        with conn:
            answer = one_error_object(interrupt(proc), 130, "interrupted")
    assert answer["mission"] == "stand up"


def test_run_json_interrupted_while_planning_is_one_json_error(tmp_path):
    """Ctrl-C while the model has not answered the plan request."""
    from tests.llm_server import ScriptedLLM, delay, json_plan

    with ScriptedLLM(models=("m",)) as srv:
        srv.script(delay(60, json_plan([{"skill": "body.stand", "args": {}}])))
        proc = start_json_run(
            "--backend",
            "llamacpp",
            "--base-url",
            srv.url,
            "--model",
            "m",
            "stand up",
            env={"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path), "SHADOWHOUND_LLM__HYBRID": "false"},
        )
        deadline = time.monotonic() + SAFETY
        while not srv.requests and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert srv.requests, "the plan request never reached the model"
        done = interrupt(proc)
    # One object either way: the stopped mission's result once planning can be abandoned at
    # once, else the error after the grace period; nothing moved.
    answer = json.loads(done.stdout)
    assert done.returncode == answer["exit_code"] == 130, done.stderr
    assert answer["success"] is False and answer["error"] and "Traceback" not in done.stderr
    assert (answer.get("robot") or {}).get("distance_travelled", 0) == 0


def test_run_json_interrupted_while_moving_is_the_result_with_an_error(tmp_path):
    proc = start_json_run(
        "--time-scale",
        "1",
        "walk backward 4 meters at 0.1 m/s",  # 40 s: the Ctrl-C lands mid-walk on any machine
        env={"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path)},
    )
    assert proc.stderr is not None
    for line in proc.stderr:  # progress: wait until the robot walks
        if "nav.move" in line:
            break
    done = interrupt(proc)
    answer = json.loads(done.stdout)  # the mission's own result: it had started
    assert done.returncode == answer["exit_code"] == 130 and answer["success"] is False
    assert answer["status"] == "stopped" and "e-stop" in answer["error"]
    assert answer["robot"]["distance_travelled"] < 4


def test_chat_estop_acts_while_a_mission_walks():
    """/estop typed while /run walks is not queued behind the mission: it stops it."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "shadowhound", "--time-scale", "1", "chat"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={k: v for k, v in os.environ.items() if k != "SHADOWHOUND_CONFIG"},
    )
    # 20 s of walking: the /estop lands while it walks on any machine.
    out, _ = proc.communicate("/run walk backward 2 meters at 0.1 m/s\n/estop\n", timeout=SAFETY)
    lines = out.strip().splitlines()
    assert proc.returncode == 0
    assert lines[0].startswith("e-stop latched")  # answered at once, before the mission's end
    assert lines[1].startswith("failed: ") and "e-stop" in lines[1], lines


def test_json_answers_are_strict_json_and_chat_status_says_the_pose_is_unknown_when_odometry_lies(
    capsys,
):
    """`run --json` prints a result with print_json: with a NaN pose it stays JSON that strict
    readers (jq) take, the pose null. Chat's /status says in words that the pose is unknown."""
    import math

    from shadowhound import RobotAgent, RobotAgentConfig
    from shadowhound.cli._base import print_json
    from shadowhound.cli.chat import _chat_line
    from shadowhound.worker import MissionWorker
    from tests.lying_odometry import LyingOdometry
    from tests.strict_json import strict_loads

    agent = RobotAgent(RobotAgentConfig(robot=LyingOdometry(x=math.nan, y=-math.inf)))
    agent.initialize()
    worker = MissionWorker(agent)
    try:
        status = _chat_line(agent, worker, "/status")
        result = agent.execute_mission("sit down")
    finally:
        worker.stop(timeout=1.0)
        agent.cleanup()
    assert "position is unknown (odometry reports x=nan, y=-inf)" in status, status
    print_json({**result.to_dict(), "exit_code": 0})
    answer = strict_loads(capsys.readouterr().out)
    assert isinstance(answer, dict) and answer["success"] is True
    assert (answer["robot"]["x"], answer["robot"]["y"]) == (None, None)


def test_chat_stop_ends_patrol_until_i_say_stop_as_asked():
    """Issue 26: a plain "stop" typed in the chat is the person's stop, at once, out of turn:
    "patrol until I say stop" ends as asked (ok)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "shadowhound", "--time-scale", "1", "chat"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={k: v for k, v in os.environ.items() if k != "SHADOWHOUND_CONFIG"},
    )
    assert proc.stdin is not None and proc.stderr is not None
    proc.stdin.write("/run patrol until I say stop\n")
    proc.stdin.flush()
    for line in proc.stderr:  # the mission's progress: its step has started
        if "nav.patrol() until I say stop ..." in line:
            break
    out, _ = proc.communicate("stop\n", timeout=SAFETY)
    lines = out.strip().splitlines()
    assert proc.returncode == 0
    assert lines[0] == "stopping 'patrol until I say stop'", lines  # at once, out of turn
    assert lines[1].startswith("ok: ") and "stopped: you said stop" in lines[1], lines
