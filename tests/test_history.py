"""Who may mark a mission in the shared history: only a process whose owner has ended.

Real separate processes on a real SQLite file: a process that owns running or queued missions
keeps them while it lives (`shadowhound history` from another process marks nothing); after it
is killed, its running mission reads `interrupted` and the missions it had accepted but not yet
started read `not_run`, with the reason.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.memory import MissionHistory, RobotId
from shadowhound.memory.history import INTERRUPTED, NEVER_STARTED
from shadowhound.worker import MissionJob, MissionWorker

ROOT = Path(__file__).parent.parent


def cli(data: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SHADOWHOUND_MEMORY__DATA_DIR": str(data)}
    env.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )


def listed(data: Path) -> dict[str, dict[str, Any]]:
    """`shadowhound history --json`, run as its own process, by mission id."""
    done = cli(data, "history", "--json", "--limit", "50")
    assert done.returncode == 0, done.stderr
    return {row["id"]: row for row in json.loads(done.stdout)}


def start(script: str) -> subprocess.Popen[str]:
    """A Python process running `script` (with this checkout's package importable)."""
    source = "import sys; sys.path.insert(0, 'src')\n" + textwrap.dedent(script)
    return subprocess.Popen(
        [sys.executable, "-c", source],
        cwd=ROOT,
        text=True,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )


def first_line(process: subprocess.Popen[str]) -> str:
    assert process.stdout is not None
    line = process.stdout.readline()
    assert line, f"the process ended first (exit {process.wait(10)})"
    return line.strip()


def kill(process: subprocess.Popen[str]) -> None:
    process.send_signal(signal.SIGKILL)
    process.wait(10)
    if process.stdout is not None:
        process.stdout.close()
    if process.stdin is not None:
        process.stdin.close()


OWNER = """
    import time
    from shadowhound.memory import MissionHistory, RobotId
    store = MissionHistory({path!r})
    store.mission_started("live1", "walk forward 3 meters", time.time(), robot=RobotId("sim"))
    print("ready", flush=True)
    sys.stdin.readline()  # hold the mission until the test kills this process
"""


def test_another_process_never_marks_a_live_owners_mission(tmp_path):
    owner = start(OWNER.format(path=str(tmp_path / "history.db")))
    try:
        assert first_line(owner) == "ready"
        assert listed(tmp_path)["live1"]["status"] == "running"  # `shadowhound history`
        reader = MissionHistory(tmp_path / "history.db")  # and an open in this process
        assert reader.interrupted == 0 and reader.get("live1")["status"] == "running"
        reader.close()
        assert listed(tmp_path)["live1"]["status"] == "running"
    finally:
        kill(owner)
    row = listed(tmp_path)["live1"]
    assert row["status"] == "interrupted" and row["response"] == INTERRUPTED


def test_a_second_handle_in_the_owning_process_marks_nothing(tmp_path):
    owner = MissionHistory(tmp_path / "history.db")
    owner.mission_started("mine", "turn left", time.time(), robot=RobotId("sim"))
    other = MissionHistory(tmp_path / "history.db")
    assert other.interrupted == 0 and other.get("mine")["status"] == "running"
    other.close()
    owner.close()  # the owner is done with it: from now on nobody runs it
    again = MissionHistory(tmp_path / "history.db")
    assert again.interrupted == 1 and again.get("mine")["status"] == "interrupted"
    again.close()


def test_rows_from_before_owners_were_recorded_are_still_marked(tmp_path):
    import sqlite3

    db = sqlite3.connect(tmp_path / "history.db")
    db.execute(
        "CREATE TABLE missions (id TEXT PRIMARY KEY, mission TEXT NOT NULL, status TEXT "
        "NOT NULL, success INTEGER, response TEXT, started_at REAL NOT NULL, "
        "finished_at REAL, record TEXT)"
    )
    db.execute(
        "INSERT INTO missions (id, mission, status, started_at) VALUES "
        "('old', 'sit', 'running', 1.0)"
    )
    db.commit()
    db.close()
    store = MissionHistory(tmp_path / "history.db")
    assert store.interrupted == 1 and store.get("old")["status"] == "interrupted"
    store.close()


# -- queued missions are on record from acceptance ----------------------------------------------

QUEUE = """
    import time
    from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
    from shadowhound.worker import MissionJob, MissionWorker
    cfg = ShadowHoundConfig(memory={{"enabled": True, "data_dir": {data!r}}})
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(cfg.sim, time_scale=1.0), settings=cfg))
    agent.initialize()
    worker = MissionWorker(agent)
    jobs = [MissionJob(text, source="web") for text in
            ("wait 60 seconds", "walk forward 1 meter", "turn left 90 degrees")]
    for job in jobs:
        assert worker.submit(job) is None
    while agent.get_diagnostics()["status"] != "executing":
        time.sleep(0.01)
    print(" ".join(job.mission_id for job in jobs), flush=True)
    sys.stdin.readline()
"""


def test_missions_queued_when_the_process_is_killed_are_listed_as_not_run(tmp_path):
    process = start(QUEUE.format(data=str(tmp_path)))
    try:
        running, *waiting = first_line(process).split()
        alive = listed(tmp_path)
        assert alive[running]["status"] == "running"
        assert [alive[m]["status"] for m in waiting] == ["queued", "queued"]
    finally:
        kill(process)
    after = listed(tmp_path)  # a new process after the hard kill
    assert after[running]["status"] == "interrupted"
    for mission in waiting:
        assert after[mission]["status"] == "not_run"
        assert after[mission]["response"] == NEVER_STARTED and after[mission]["success"] == 0
    assert {after[m]["mission"] for m in waiting} == {
        "walk forward 1 meter",
        "turn left 90 degrees",
    }


def _worker(data: Path) -> tuple[RobotAgent, MissionWorker]:
    cfg = ShadowHoundConfig(memory={"enabled": True, "data_dir": str(data)})
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(cfg.sim, time_scale=1.0), settings=cfg))
    agent.initialize()
    return agent, MissionWorker(agent)


def _running(agent: RobotAgent) -> None:
    deadline = time.monotonic() + 10
    while agent.get_diagnostics()["status"] != "executing" and time.monotonic() < deadline:
        time.sleep(0.01)


def test_waiting_missions_are_listed_but_kept_out_of_prompts_and_chat(tmp_path):
    agent, worker = _worker(tmp_path)
    running, waiting = MissionJob("wait 60 seconds"), MissionJob("walk forward 1 meter")
    assert worker.submit(running) is None and worker.submit(waiting) is None
    _running(agent)
    history = agent.memory.history
    assert history is not None
    listed = {r["mission"]: r["status"] for r in history.recent()}  # `shadowhound history`
    assert listed == {"wait 60 seconds": "running", "walk forward 1 meter": "queued"}
    assert not any("walk forward" in line for line in agent.recent_summaries())
    assert "wait 60 seconds" in " ".join(agent.recent_summaries())
    worker.stop()
    agent.cleanup()


def test_a_queued_mission_cancelled_before_its_turn_is_not_run(tmp_path):
    agent, worker = _worker(tmp_path)
    running, skipped = MissionJob("wait 60 seconds"), MissionJob("walk forward 1 meter")
    assert worker.submit(running) is None and worker.submit(skipped) is None
    history = agent.memory.history
    assert history is not None and history.get(skipped.mission_id)["status"] == "queued"
    _running(agent)
    skipped.cancelled.set()
    agent.cancel()
    assert skipped.done.wait(10)
    assert history.get(running.mission_id)["status"] == "stopped"
    record = history.get(skipped.mission_id)
    assert record["status"] == "not_run" and "cancelled before it started" in record["response"]
    worker.stop()
    agent.cleanup()


def test_queued_missions_dropped_by_the_estop_say_why_and_dry_runs_leave_none(tmp_path):
    agent, worker = _worker(tmp_path)
    running, dropped = MissionJob("wait 60 seconds"), MissionJob("turn left 90 degrees")
    dry = MissionJob("walk forward 2 meters", dry_run=True)
    for job in (running, dropped, dry):
        assert worker.submit(job) is None
    history = agent.memory.history
    assert history is not None and history.get(dry.mission_id) is None  # moves nothing
    _running(agent)
    agent.estop()
    assert len(worker.drop_queued("the e-stop was pressed before it started")) == 2
    assert running.done.wait(10)
    assert history.get(running.mission_id)["status"] == "stopped"
    record = history.get(dropped.mission_id)
    assert record["status"] == "not_run" and "e-stop was pressed" in record["response"]
    assert history.get(dry.mission_id) is None
    worker.stop()
    agent.release_estop()
    agent.cleanup()


def test_a_queued_mission_the_agent_refuses_is_not_run_with_the_refusal(tmp_path):
    agent, worker = _worker(tmp_path)
    first, second = MissionJob("wait 60 seconds"), MissionJob("walk forward 1 meter")
    assert worker.submit(first) is None and worker.submit(second) is None
    _running(agent)
    agent.estop()  # latched: the queued mission is refused when its turn comes
    assert second.done.wait(10)
    record = agent.memory.history.get(second.mission_id)
    assert record["status"] == "not_run" and "e-stop is latched" in record["response"]
    worker.stop()
    agent.release_estop()
    agent.cleanup()


@pytest.mark.parametrize("way", ["submit", "start_now"])  # topic and web; action goals
def test_both_ways_of_accepting_record_at_acceptance(tmp_path, way):
    agent, worker = _worker(tmp_path)
    job = MissionJob("wait 60 seconds")
    assert getattr(worker, way)(job) is None
    assert agent.memory.history.get(job.mission_id)["status"] in ("queued", "running")
    worker.stop()
    agent.cleanup()
