"""Memory: persistent history and places (SQLite) and retrieval memory (Chroma, MiniLM)."""

from __future__ import annotations

import json
import math
import os
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.config import ConfigError
from shadowhound.memory import MemoryStoreError, MissionHistory, RobotId
from tests.strict_json import strict_loads

try:
    import chromadb  # noqa: F401

    from shadowhound.memory.embedding import model_dir

    model_dir()
    HAVE_RAG = True
except ImportError:
    HAVE_RAG = False
SIM = RobotId("sim")  # the robot the offline profile drives
needs_rag = pytest.mark.skipif(
    not HAVE_RAG and not os.environ.get("CI") or sys.version_info < (3, 11) and not HAVE_RAG,
    reason="retrieval memory needs the 'memory' extra",
)


def agent_with_memory(data: Path, **memory) -> RobotAgent:
    settings = load_config(
        "offline", {"memory": {"enabled": True, "data_dir": str(data), **memory}}, environ={}
    )
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
    agent.initialize()
    return agent


def cli(
    data: Path, *args: str, stdin: str | None = None, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "SHADOWHOUND_MEMORY__DATA_DIR": str(data), **(env or {})}
    env.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        input=stdin,
    )


# -- history ------------------------------------------------------------------------------------


def test_history_survives_process_restarts(tmp_path):
    assert cli(tmp_path, "run", "-q", "walk forward 1 meter").returncode == 0
    assert cli(tmp_path, "run", "-q", "walk forward 500 meters").returncode == 1
    listed = json.loads(cli(tmp_path, "history", "--json").stdout)
    assert [r["mission"] for r in listed] == ["walk forward 500 meters", "walk forward 1 meter"]
    assert [r["status"] for r in listed] == ["failed", "succeeded"]
    full = json.loads(cli(tmp_path, "history", listed[1]["id"]).stdout)
    assert full["steps"][0]["skill"] == "nav.move" and full["steps"][0]["status"] == "succeeded"
    assert full["timing"]["total_duration"] > 0 and full["usage"]["round_trips"] == 0
    refused = json.loads(cli(tmp_path, "history", listed[0]["id"]).stdout)
    assert refused["refusals"] and "geofence" in " ".join(refused["refusals"])
    chat = cli(tmp_path, "chat", stdin="what did you do last?\n")
    assert "walk forward 1 meter" in chat.stdout and "walk forward 500 meters" in chat.stdout


def test_a_mission_running_when_the_process_died_is_marked_interrupted(tmp_path):
    store = MissionHistory(tmp_path / "history.db")
    store.mission_started("dead1", "walk forward 3 meters", time.time(), robot=SIM)
    store.close()  # the process "dies" here: no mission_finished
    again = MissionHistory(tmp_path / "history.db")
    assert again.interrupted == 1
    assert again.get("dead1")["status"] == "interrupted"


def test_concurrent_writers_in_threads_and_processes(tmp_path):
    path = tmp_path / "history.db"
    store = MissionHistory(path)
    other = subprocess.Popen(
        [
            sys.executable,
            "-c",
            (
                "import sys, time; sys.path.insert(0, 'src');"
                "from shadowhound.memory import MissionHistory, RobotId;"
                f"s = MissionHistory({str(path)!r});"
                "[s.mission_started(f'proc{i}', 'from another process', time.time(), "
                "robot=RobotId('sim')) for i in range(50)];"
                "s.close()"
            ),
        ],
        cwd=Path(__file__).parent.parent,
    )

    def writer(n: int) -> None:
        for i in range(25):
            store.mission_started(f"t{n}-{i}", f"thread {n}", time.time(), robot=SIM)

    threads = [threading.Thread(target=writer, args=(n,)) for n in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert other.wait(60) == 0
    assert store.count() == 150 and store.unsaved == 0


def test_a_locked_database_loses_no_record(tmp_path):
    path = tmp_path / "history.db"
    agent = agent_with_memory(tmp_path)
    agent.memory.history._db.execute("PRAGMA busy_timeout = 50")
    blocker = sqlite3.connect(str(path), timeout=0)
    blocker.execute("BEGIN EXCLUSIVE")  # another process holds the write lock
    result = agent.execute_mission("walk forward 1 meter")
    assert result.success  # the robot's mission does not depend on the history file
    # started + finished (+ the objects first seen at the start), kept for a retry
    assert agent.memory.history.unsaved >= 2
    blocker.rollback()
    blocker.close()
    agent.execute_mission("turn left")
    assert agent.memory.history.unsaved == 0
    assert [r["mission"] for r in agent.recent_missions(5)] == ["turn left", "walk forward 1 meter"]


def test_a_record_the_database_refuses_for_good_is_set_aside_and_later_ones_land(tmp_path):
    """A place at x = NaN (SQLite stores NaN as NULL: NOT NULL refuses it) and a time beyond
    64 bits used to stay at the head of the backlog, and nothing after them was written."""
    path = tmp_path / "history.db"
    store = MissionHistory(path)
    store._db.execute("PRAGMA busy_timeout = 50")
    blocker = sqlite3.connect(str(path), timeout=0)
    blocker.execute("BEGIN EXCLUSIVE")  # first the database is locked: every write waits
    store.mission_started("m1", "walk forward 1 meter", time.time(), robot=SIM)
    store.save_place(SIM, "den", math.nan, 1.0, 0.0)
    store.mission_queued("m2", "from a clock that lies", 2**70, robot=SIM)
    assert store.unsaved == 3  # kept, in order, for a retry
    blocker.rollback()
    blocker.close()
    store.save_place(SIM, "desk", 2.0, 1.0, 0.0)  # the retry: the good ones land, the bad go aside
    assert store.unsaved == 0
    finished = {
        "mission_id": "m3",
        "mission": "stand up",
        "status": "succeeded",
        "success": True,
        "response": "done",
        "timing": {"total_duration": 1.0},
        "robot": {"x": math.nan, "yaw": math.inf, "y": 0.5},
    }
    store.mission_finished(finished, time.time(), robot=SIM)
    store.mission_finished({"mission_id": "m4", "mission": "no status"}, time.time(), robot=SIM)
    store.close()

    again = MissionHistory(path)
    assert sorted(r["id"] for r in again.recent()) == ["m1", "m3"]
    assert again.load_places(SIM) == {"desk": (2.0, 1.0, 0.0)}
    record = again.get("m3")
    assert record is not None and record["robot"] == {"x": None, "yaw": None, "y": 0.5}
    assert strict_loads(again._query("SELECT record FROM missions WHERE id = 'm3'", ())[0][0])
    lines = [strict_loads(line) for line in again.rejected.read_text().splitlines()]
    assert again.rejected == tmp_path / "history.rejected.jsonl"
    assert again.rejected_count() == 3
    assert [line["what"] for line in lines] == [
        "place 'den'",
        "queued mission m2",
        "finished mission m4",  # a record that cannot be made into a row
    ]
    assert lines[0]["error"] == "IntegrityError: NOT NULL constraint failed: places.x"
    assert lines[0]["params"][:3] == ["sim", "den", None]  # strict JSON: the NaN is null
    assert lines[1]["error"].startswith("OverflowError:") and lines[1]["params"][2] == 2**70
    assert lines[2]["error"] == "KeyError: 'status'"
    assert lines[2]["params"] == [{"mission_id": "m4", "mission": "no status"}]
    again.close()
    listed = cli(tmp_path, "history")
    assert listed.returncode == 0 and "walk forward 1 meter" in listed.stdout
    assert (
        f"3 record(s) the history database refused are set aside in {again.rejected}"
        in listed.stderr
    )


def test_records_waiting_at_close_are_written_or_set_aside(tmp_path):
    path = tmp_path / "history.db"
    store = MissionHistory(path)
    store._db.execute("PRAGMA busy_timeout = 50")
    blocker = sqlite3.connect(str(path), timeout=0)
    blocker.execute("BEGIN EXCLUSIVE")
    store.save_place(SIM, "den", 1.0, math.nan, 0.0)
    store.mission_started("m1", "turn left", time.time(), robot=SIM)
    blocker.rollback()
    blocker.close()
    store.close()  # nothing written since the lock: close writes what waits
    again = MissionHistory(path)
    assert [r["id"] for r in again.recent()] == ["m1"] and again.load_places(SIM) == {}
    assert again.rejected_count() == 1
    again.close()


def test_a_refused_record_that_cannot_be_set_aside_is_logged_in_full(tmp_path, caplog):
    store = MissionHistory(tmp_path / "history.db")
    store.rejected.mkdir()  # the side file cannot be written
    with caplog.at_level("ERROR"):
        store.save_place(SIM, "den", math.nan, 1.0, 0.0)
        store.save_place(SIM, "desk", 2.0, 1.0, 0.0)
    assert store.unsaved == 0 and store.load_places(SIM) == {"desk": (2.0, 1.0, 0.0)}
    assert "cannot be set aside" in caplog.text and '"params": ["sim", "den", null' in caplog.text
    store.close()


def test_a_corrupt_database_is_a_clear_error_and_is_kept(tmp_path):
    path = tmp_path / "history.db"
    path.write_bytes(b"this is not a database" * 100)
    with pytest.raises(ConfigError, match="is corrupt .* move it aside"):
        agent_with_memory(tmp_path)
    proc = cli(tmp_path, "run", "stand up")
    assert proc.returncode == 2 and "is corrupt" in proc.stderr
    assert path.read_bytes() == b"this is not a database" * 100
    with pytest.raises(MemoryStoreError, match="corrupt"):
        MissionHistory(path)


def test_retention_prunes_old_missions(tmp_path):
    store = MissionHistory(tmp_path / "history.db")
    for i in range(5):
        store.mission_started(f"old{i}", "long ago", time.time() - 200 * 86400, robot=SIM)
    for i in range(5):
        store.mission_started(f"new{i}", "today", time.time(), robot=SIM)
    assert store.prune(max_age_days=90, max_missions=3) == 7
    assert [r["mission"] for r in store.recent()] == ["today"] * 3


# -- places -------------------------------------------------------------------------------------


def test_teach_a_place_restart_and_go_there(tmp_path):
    taught = cli(
        tmp_path,
        "run",
        "-q",
        "walk forward 2 meters, turn left and walk 1 meter, then remember this spot as the desk",
    )
    assert taught.returncode == 0 and "remembered this spot as the desk" in taught.stdout
    places = {p["name"]: p for p in json.loads(cli(tmp_path, "places", "--json").stdout)}
    assert places["desk"]["source"] == "taught" and places["desk"]["robot_id"] == "sim"
    assert places["desk"]["goal"] and places["desk"]["x"] == pytest.approx(2.0, abs=0.01)
    went = json.loads(cli(tmp_path, "run", "--json", "go to the desk").stdout)
    assert went["success"]
    assert (went["robot"]["x"], went["robot"]["y"]) == (
        pytest.approx(2.0, abs=0.01),
        pytest.approx(1.0, abs=0.01),
    )
    assert cli(tmp_path, "run", "-q", "forget the desk").returncode == 0
    gone = cli(tmp_path, "run", "-q", "go to the desk")  # no such place, nor a thing it knows
    assert gone.returncode == 1 and "'desk' is not a place or an object I know" in gone.stdout


def test_a_place_taught_in_a_plan_is_usable_later_in_the_same_plan(tmp_path):
    agent = agent_with_memory(tmp_path)
    result = agent.execute_mission(
        "walk forward 1 meter, remember this spot as the door, "
        "walk forward 1 meter, then go to the door"
    )
    assert result.success, result.response
    assert agent.robot.get_state().x == pytest.approx(1.0, abs=0.01)


def test_places_without_memory_last_for_the_process():
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0)))
    result = agent.execute_mission("remember this spot as the dock")
    assert result.success and "for this session" in result.response
    assert not agent.execute_mission("forget the lab").success


# -- retrieval memory ---------------------------------------------------------------------------


@needs_rag
def test_retrieval_is_semantic_and_persistent(tmp_path):
    from shadowhound.memory.embedding import MiniLMEmbedder
    from shadowhound.memory.recall import RecallMemory

    embedder = MiniLMEmbedder()
    memory = RecallMemory(tmp_path / "recall", embedder, robot=SIM)
    memory.add("the fridge is in the kitchen", "fact")
    noise = [
        "the charging dock is next to the sofa",
        "the red ball rolled under the table",
        "it rained in the afternoon",
        "the door to the garden is blue",
        "the operator prefers slow walking",
        "battery was at 80% after the patrol",
        "a person stood in the hallway",
        "the plant needs water",
    ]
    memory.add_many([(text, "observation", {}) for text in noise])
    top = memory.search("where is the fridge?", k=3)
    assert top[0].text == "the fridge is in the kitchen" and top[0].score > top[1].score
    again = RecallMemory(tmp_path / "recall", embedder, robot=SIM)  # as a new process would
    assert again.count() == 9
    assert again.search("where is the fridge?", k=1)[0].kind == "fact"


@needs_rag
def test_agent_learns_facts_and_observations(tmp_path):
    agent = agent_with_memory(tmp_path, enable_rag=True)
    assert agent.execute_mission("remember that the fridge is in the kitchen").success
    agent.execute_mission("what do you see?")
    answer = agent.execute_mission("where is the fridge?")
    assert answer.success and "the fridge is in the kitchen" in answer.response
    seen = agent.chat("what did you see earlier?")
    assert "red ball" in seen


@needs_rag
def test_language_model_gets_relevant_memories(tmp_path):
    from tests.llm_server import ScriptedLLM, json_plan

    with ScriptedLLM(models=("m",)) as srv:
        settings = load_config(
            "llamacpp",
            {
                "llm": {"base_url": srv.url, "model": "m", "hybrid": False},
                "memory": {"enabled": True, "enable_rag": True, "data_dir": str(tmp_path)},
            },
            environ={},
        )
        agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
        agent.initialize()
        agent.memory.recall.add("the charging dock is behind the sofa", "fact")
        srv.script(json_plan([{"skill": "sys.status", "args": {}}]))
        agent.execute_mission("where is the charging dock?")
        system = srv.requests[0]["messages"][0]["content"]
        assert "Relevant memories:" in system and "behind the sofa" in system


def break_store(data: Path, damage: str) -> Path:
    """A retrieval store made unusable the way it happens to people; returns its path."""
    store = data / "recall"
    if damage == "corrupt":  # a real store, then its database overwritten (a bad disk, a bad copy)
        agent = agent_with_memory(data, enable_rag=True)
        assert agent.execute_mission("remember that the fridge is in the kitchen").success
        agent.cleanup()
        (store / "chroma.sqlite3").write_bytes(b"this is not a database" * 200)
    else:  # a file where the directory should be
        store.write_text("not a directory")
    return store


@needs_rag
@pytest.mark.parametrize("damage", ["corrupt", "file"])
def test_a_broken_retrieval_store_turns_recall_off_and_missions_still_run(tmp_path, damage):
    store = break_store(tmp_path, damage)
    kept = store.read_bytes() if store.is_file() else (store / "chroma.sqlite3").read_bytes()
    rag = {"SHADOWHOUND_MEMORY__ENABLE_RAG": "true"}

    proc = cli(tmp_path, "run", "--json", "walk forward 1 meter", env=rag)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["success"] is True
    assert "retrieval memory is off for this run" in proc.stderr and str(store) in proc.stderr
    assert "Traceback" not in proc.stderr

    proc = cli(tmp_path, "recall", "where is the fridge?", env=rag)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "retrieval memory is unavailable" in proc.stderr and str(store) in proc.stderr
    assert "move it aside" in proc.stderr and "memory.enable_rag: false" in proc.stderr
    assert "Traceback" not in proc.stderr

    agent = agent_with_memory(tmp_path, enable_rag=True)
    status = agent.get_diagnostics()["memory"]
    assert status["history"] == "on" and status["recall"] == "unavailable"
    assert str(store) in status["recall_problem"]
    taught = agent.execute_mission("remember that the sofa is blue")
    assert not taught.success and "retrieval memory is off for this run" in taught.response
    assert agent.execute_mission("walk forward 1 meter").success
    agent.cleanup()
    # The broken store is left as it was, for inspection.
    assert kept == (
        store.read_bytes() if store.is_file() else (store / "chroma.sqlite3").read_bytes()
    )


@needs_rag
def test_a_store_that_breaks_while_running_turns_recall_off(tmp_path):
    agent = agent_with_memory(tmp_path, enable_rag=True)
    assert agent.execute_mission("remember that the fridge is in the kitchen").success
    assert agent.get_diagnostics()["memory"]["recall"] == "on"
    with (tmp_path / "recall" / "chroma.sqlite3").open("r+b") as db:
        db.write(b"\0garbage" * 20_000)
    answer = agent.execute_mission("where is the fridge?")  # searches the broken store
    assert answer.success
    assert agent.execute_mission("walk forward 1 meter").success  # its summary is not stored
    status = agent.get_diagnostics()["memory"]
    assert status["recall"] == "unavailable" and "recall" in status["recall_problem"]
    assert [r["mission"] for r in agent.recent_missions(3)][:2] == [
        "walk forward 1 meter",
        "where is the fridge?",
    ]
    agent.cleanup()


def test_rag_without_the_extra_says_what_to_install(tmp_path):
    code = (
        "import sys; sys.modules['chromadb'] = None\n"
        "from shadowhound import RobotAgent, load_config\n"
        f"s = load_config('offline', {{'memory': {{'enable_rag': True, 'data_dir': "
        f"{str(tmp_path)!r}}}}})\n"
        "try:\n    RobotAgent(s).initialize()\n"
        "except Exception as e:\n    print(type(e).__name__, e)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60
    ).stdout
    assert out.startswith("ConfigError") and "pip install 'shadowhound[memory]'" in out


@needs_rag
def test_numpy_minilm_matches_sentence_transformers():
    """Reference vectors were computed once with sentence-transformers and torch (see the
    file's `source`); the NumPy encoder must give the same embeddings."""
    import numpy as np

    from shadowhound.memory.embedding import MiniLMEmbedder

    reference = json.loads((Path(__file__).parent / "data" / "minilm_reference.json").read_text())
    ours = MiniLMEmbedder().embed(reference["texts"])
    expected = np.array(reference["embeddings"], dtype=np.float32)
    assert ours.shape == (4, 384)
    assert np.abs(ours - expected).max() < 1e-5
