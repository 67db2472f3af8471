"""Memory belongs to the robot that made it (issue 32, item 3): a robot's identity, every place,
sighting and mission carrying it, goals only from the current robot's own memories, other
robots' shown as history, and history databases of an older version migrated in place.

Judged by the simulator's truth (`SimRobot.true_path`), never by what the agent says."""

from __future__ import annotations

import json
import math
import os
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, SimRobot, load_config
from shadowhound.config import ConfigError, ShadowHoundConfig
from shadowhound.errors import ClaimError, PlanProblem
from shadowhound.memory import MissionHistory, RobotId
from shadowhound.memory.service import AgentMemory
from shadowhound.robot.sim.scene import DEFAULT_WORLD, World
from shadowhound.ros.params import parse_parameters
from shadowhound.skills import objects

from .test_memory import needs_rag

CHAIR = DEFAULT_WORLD.find("yellow chair")
assert CHAIR is not None
# The house as a robot without the chair in view sees it (a Go2 with no detector sees nothing):
# whatever it walks to, it walks to from memory.
NO_CHAIR = World(objects=tuple(o for o in DEFAULT_WORLD.objects if o is not CHAIR))


def settings_for(data: Path, robot: dict[str, str] | str = "sim") -> ShadowHoundConfig:
    return load_config(
        "offline",
        {"robot": robot, "memory": {"enabled": True, "data_dir": str(data)}},
        environ={},
    )


def agent_on(data: Path, robot: dict[str, str] | str, world: World = DEFAULT_WORLD) -> RobotAgent:
    sim = SimRobot(time_scale=0.0, world=world)
    agent = RobotAgent(RobotAgentConfig(robot=sim, settings=settings_for(data, robot)))
    agent.initialize()
    return agent


def truth(agent: RobotAgent) -> tuple[float, float]:
    robot = agent.robot
    assert isinstance(robot, SimRobot)
    _t, x, y = robot.true_path[-1]
    return x, y


# -- who a robot is ------------------------------------------------------------------------------


def test_a_robot_is_its_name_else_its_type_and_namespace() -> None:
    def identity(robot: object, environ: dict[str, str] | None = None) -> str:
        overrides = {"robot": robot} if robot else {}
        return load_config("offline", overrides, environ=environ or {}).robot.identity.name

    assert identity("sim") == "sim"
    assert identity("go2") == "go2"
    assert identity("go2_edu") == "go2_edu"
    assert identity({"type": "go2", "namespace": "robot0"}) == "go2:robot0"
    assert identity({"type": "go2", "namespace": "/robot1"}) == "go2:robot1"
    assert identity({"type": "go2_edu", "namespace": "robot0"}) == "go2_edu:robot0"
    assert identity({"type": "go2", "name": "kitchen-dog"}) == "kitchen-dog"
    assert identity(None, {"SHADOWHOUND_ROBOT__NAME": "bench-sim"}) == "bench-sim"
    with pytest.raises(ConfigError, match="a robot's name is 1 to 64 letters, digits and _"):
        identity({"type": "sim", "name": "my robot"})
    with pytest.raises(ConfigError, match=r"'go2:a b' \(made of the namespace\): set robot.name"):
        identity({"type": "go2", "namespace": "a b"})


def test_a_robot_of_another_type_never_takes_the_profiles_name(tmp_path: Path) -> None:
    """A profile naming its simulator: a Go2 chosen on top of it (the node's robot:=go2, an
    environment variable) is not that simulator."""
    profile = tmp_path / "named.yaml"
    profile.write_text("backend: offline\nrobot: {type: sim, name: lab-sim}\n")
    assert load_config(str(profile), environ={}).robot.identity.name == "lab-sim"
    go2 = load_config(str(profile), {"robot": {"type": "go2"}}, environ={})
    assert go2.robot.identity.name == "go2"
    env = load_config(str(profile), environ={"SHADOWHOUND_ROBOT__TYPE": "go2_edu"})
    assert env.robot.identity.name == "go2_edu"


def test_the_nodes_robot_name_parameter_names_the_robot(tmp_path: Path) -> None:
    def named(**values: object) -> str:
        return parse_parameters(values).agent_settings().robot.identity.name

    assert named() == "sim"
    assert named(robot="go2") == "go2"
    assert named(robot="go2", robot_namespace="robot0") == "go2:robot0"
    assert named(robot="go2", robot_namespace="robot0", robot_name="rex") == "rex"
    assert named(robot="go2_edu", robot_name="edu-1") == "edu-1"
    assert named(robot="sim", robot_name="sim-2") == "sim-2"
    profile = tmp_path / "named.yaml"
    profile.write_text("backend: offline\nrobot: {type: sim, name: lab-sim}\n")
    assert named(backend_config=str(profile)) == "lab-sim"  # the profile's own robot
    assert named(backend_config=str(profile), robot="go2") == "go2"  # another robot
    with pytest.raises(ConfigError, match="robot_name 'a b' is not a robot's name"):
        parse_parameters({"robot_name": "a b"})


# -- goals only from this robot's memories ------------------------------------------------------

ROBOTS = ["sim", "go2", "go2:robot0", "go2_edu"]
NAMES = ["lamp", "desk", "red lamp", "shelf", "bin"]  # none of them in the empty room
EMPTY = World(objects=())
_spot = st.floats(-4.0, 4.0).map(lambda v: round(v, 2))
memories = st.lists(
    st.tuples(
        st.sampled_from([*ROBOTS, None]),  # None: a row from before robots were recorded
        st.sampled_from(["place", "sighting"]),
        st.sampled_from(NAMES),
        _spot,
        _spot,
    ),
    max_size=12,
)


def store_rows(path: Path, rows: list[tuple[str | None, str, str, float, float]]) -> None:
    store = MissionHistory(path)
    for who, kind, name, x, y in rows:
        if who is None:
            continue
        if kind == "place":
            store.save_place(RobotId(who), name, x, y, 0.0)
        else:
            store.save_sighting(RobotId(who), name, x, y, 0.25, 1.0, 0.0)
    store.close()
    with sqlite3.connect(path) as db:  # rows of no known robot, as the migration leaves them
        for who, kind, name, x, y in rows:
            if who is None and kind == "place":
                db.execute(
                    "INSERT INTO places (robot_id, name, x, y, yaw, created_at) "
                    "VALUES (NULL, ?, ?, ?, 0, 0)",
                    (name, x, y),
                )
            elif who is None:
                db.execute(
                    "INSERT INTO sightings (robot_id, name, x, y, radius, confidence, stamp, "
                    "seen_at) VALUES (NULL, ?, ?, ?, 0.25, 1, 0, 0)",
                    (name, x, y),
                )
    db.close()


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rows=memories, robot=st.sampled_from(ROBOTS), asked=st.sampled_from(NAMES))
def test_a_goal_comes_only_from_this_robots_own_memories(
    tmp_path_factory: pytest.TempPathFactory,
    rows: list[tuple[str | None, str, str, float, float]],
    robot: str,
    asked: str,
) -> None:
    """Whatever mix of robots' places and sightings the store holds (and rows of no known
    robot), what a name resolves to for robot R (the resolver every go-to uses, over the world
    model and places a mission starts with) is R's own place or sighting, or nothing."""
    data = tmp_path_factory.mktemp("mix")
    store_rows(data / "history.db", rows)
    agent = agent_on(data, {"type": "sim", "name": robot}, EMPTY)
    try:
        run = agent._new_run(f"go to the {asked}", agent.planner, None)  # the mission's start
        assert run.read(moving=False) is None
        assert run.env is not None
        mine = {(k, n): (x, y) for who, k, n, x, y in rows if who == robot}  # the latest wins
        try:
            target = objects.resolve(run.env, asked)
        except PlanProblem as exc:  # nothing of R's by that name: refused, saying whose it is
            assert ("place", asked) not in mine
            assert not any(
                k == "sighting" and (n == asked or n.endswith(" " + asked)) for k, n in mine
            ), mine
            for who, _k, n, _x, _y in rows:
                if who != robot and n == asked:
                    said = "before robots were recorded" if who is None else f"robot {who!r}"
                    assert said in str(exc), str(exc)
            return
        if target.point is not None:
            assert ("place", asked) in mine, f"a place of another robot: {target}"
            assert target.point == mine[("place", asked)], (target, rows)
        else:
            assert target.known is not None, target  # the empty room: nothing to search for
            found = target.known
            assert ("place", asked) not in mine
            assert ("sighting", found.name) in mine, f"another robot's sighting: {found}"
            assert (found.x, found.y) == mine[("sighting", found.name)], (found, rows)
    finally:
        agent.cleanup()


def test_what_another_robot_saw_is_never_walked_to(tmp_path: Path) -> None:
    """The issue's case without hardware: "go to the chair" on the simulator, then, from the same
    home, a robot of another name that cannot see the chair: it does not walk to where the
    simulator's chair was, and says why. Its own truth did not move."""
    sim = agent_on(tmp_path, "sim")
    went = sim.execute_mission("go to the chair")
    assert went.success, went.response
    x, y = truth(sim)
    assert math.hypot(x - CHAIR.x, y - CHAIR.y) < CHAIR.radius + 0.7, (x, y)
    sim.cleanup()

    go2 = agent_on(tmp_path, "go2", NO_CHAIR)  # a Go2's settings, driving a simulator
    start = truth(go2)
    asked = go2.execute_mission("go to the chair")
    end = truth(go2)
    assert not asked.success, asked.response
    assert "The yellow chair was seen by robot 'sim', not by this robot: not a goal" in (
        asked.response
    )
    assert "remembered from an earlier mission" not in asked.response
    assert math.dist(start, end) < 0.01, (start, end)
    # ... and the simulator, back in the same home, still goes there from memory.
    sim = agent_on(tmp_path, "sim", NO_CHAIR)
    planned = sim.dry_run("go to the chair")
    assert planned.success, planned.response
    sim.cleanup()
    go2.cleanup()


def test_a_robot_that_can_see_the_thing_looks_for_it_itself(tmp_path: Path) -> None:
    """Another robot's sighting is not even a first guess: a robot whose camera knows chairs
    searches, finds the chair with its own eyes, and says whose sighting it did not use."""
    sim = agent_on(tmp_path, "sim")
    assert sim.execute_mission("go to the chair").success
    sim.cleanup()
    go2 = agent_on(tmp_path, "go2")
    went = go2.execute_mission("go to the chair")
    assert went.success, went.response
    assert "The yellow chair was seen by robot 'sim', not by this robot: not a goal" in (
        went.response
    )
    assert "found the yellow chair" in went.response  # its own search
    assert "remembered from an earlier mission" not in went.response
    x, y = truth(go2)
    assert math.hypot(x - CHAIR.x, y - CHAIR.y) == pytest.approx(CHAIR.radius + 0.6, abs=0.05)
    go2.cleanup()


def test_a_place_taught_to_one_robot_is_not_anothers(tmp_path: Path) -> None:
    sim = agent_on(tmp_path, "sim")
    assert sim.execute_mission("walk forward 1 meter, remember this spot as the desk").success
    sim.cleanup()
    other = agent_on(tmp_path, {"type": "sim", "name": "go2"})
    went = other.execute_mission("go to the desk")
    assert not went.success and "The desk was taught by robot 'sim'" in went.response
    assert math.dist(truth(other), (0.0, 0.0)) < 0.01
    assert "desk" not in other.memory.places.all()
    # Each robot may have its own desk; forgetting one leaves the other's.
    assert other.execute_mission("walk backward 1 meter, remember this spot as the desk").success
    assert other.execute_mission("forget the desk").success
    other.cleanup()
    sim = agent_on(tmp_path, "sim")
    assert sim.memory.places.all()["desk"][:2] == pytest.approx((1.0, 0.0), abs=0.01)
    sim.cleanup()


def test_missions_are_recorded_with_their_robot_and_prompts_see_only_their_own(
    tmp_path: Path,
) -> None:
    sim = agent_on(tmp_path, "sim")
    assert sim.execute_mission("walk forward 1 meter").success
    sim.cleanup()
    go2 = agent_on(tmp_path, {"type": "sim", "name": "go2"})
    assert go2.execute_mission("turn left 90 degrees").success
    assert [r["mission"] for r in go2.recent_missions()] == ["turn left 90 degrees"]
    assert go2.memory.search("walk forward") == []  # the keyword fallback: its own only
    everyone = go2.memory.history.recent()
    assert {r["mission"]: r["robot_id"] for r in everyone} == {
        "walk forward 1 meter": "sim",
        "turn left 90 degrees": "go2",
    }
    assert go2.memory.history.get(everyone[0]["id"])["robot_id"] == "go2"
    assert go2.get_diagnostics()["memory"]["robot_id"] == "go2"
    go2.cleanup()


@needs_rag
def test_retrieval_memory_finds_only_this_robots_memories(tmp_path: Path) -> None:
    import chromadb
    from chromadb.config import Settings

    from shadowhound.memory.embedding import MiniLMEmbedder
    from shadowhound.memory.recall import RecallMemory, collection_name

    embedder = MiniLMEmbedder()
    store = tmp_path / "recall"
    # A memory the version before robots wrote, in its collection: no robot's.
    client = chromadb.PersistentClient(
        path=str(store), settings=Settings(anonymized_telemetry=False)
    )
    old = client.get_or_create_collection(collection_name(embedder, None), embedding_function=None)
    old.add(
        ids=["old"],
        documents=["the fridge is in the cellar"],
        embeddings=list(embedder.embed(["the fridge is in the cellar"])),
        metadatas=[{"kind": "fact", "created": 0.0}],
    )
    sim = RecallMemory(store, embedder, robot=RobotId("sim"))
    go2 = RecallMemory(store, embedder, robot=RobotId("go2:robot0"))
    similar = RecallMemory(store, embedder, robot=RobotId("go2-robot0"))  # spelt alike
    sim.add("the fridge is in the kitchen", "fact")
    go2.add("the fridge is in the garage", "fact", robot_id="sim")  # whose is not meta's
    assert [m.text for m in sim.search("where is the fridge?", k=5)] == [
        "the fridge is in the kitchen"
    ]
    theirs = go2.search("where is the fridge?", k=5, kind="fact")
    assert [m.text for m in theirs] == ["the fridge is in the garage"]
    assert similar.search("where is the fridge?", k=5) == []
    assert (sim.count(), go2.count(), similar.count(), old.count()) == (1, 1, 0, 1)


# -- an older version's database, migrated in place ---------------------------------------------

# The schema the version before robots wrote (src/shadowhound/memory/history.py, verbatim).
OLD_SCHEMA = """
CREATE TABLE IF NOT EXISTS missions (
    id TEXT PRIMARY KEY,
    mission TEXT NOT NULL,
    status TEXT NOT NULL,
    success INTEGER,
    response TEXT,
    started_at REAL NOT NULL,
    finished_at REAL,
    record TEXT,
    owner TEXT
);
CREATE INDEX IF NOT EXISTS missions_started ON missions (started_at);
CREATE TABLE IF NOT EXISTS places (
    name TEXT PRIMARY KEY,
    x REAL NOT NULL,
    y REAL NOT NULL,
    yaw REAL NOT NULL,
    created_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS sightings (
    name TEXT PRIMARY KEY,
    x REAL NOT NULL,
    y REAL NOT NULL,
    radius REAL NOT NULL,
    confidence REAL NOT NULL,
    stamp REAL NOT NULL,
    seen_at REAL NOT NULL
);
"""


def old_database(path: Path) -> None:
    """A history.db as the version before robots left it: two missions, a place, a sighting."""
    then = time.time() - 3600  # within the retention time
    with sqlite3.connect(path) as db:
        db.executescript(OLD_SCHEMA)
        db.execute(
            "INSERT INTO missions VALUES ('m1', 'go to the chair', 'succeeded', 1, "
            "'reached the yellow chair', ?, ?, '{\"mission\": \"go to the chair\"}', NULL)",
            (then, then + 30),
        )
        db.execute(
            "INSERT INTO missions VALUES ('m2', 'remember this spot as the desk', 'succeeded', "
            "1, 'remembered', ?, ?, NULL, NULL)",
            (then + 100, then + 101),
        )
        db.execute("INSERT INTO places VALUES ('desk', 1.0, 2.0, 0.5, ?)", (then + 100,))
        db.execute(
            "INSERT INTO sightings VALUES ('yellow chair', -2.0, 3.0, 0.4, 1.0, 12.0, ?)",
            (then + 20,),
        )
    db.close()


def test_an_old_database_keeps_every_row_and_none_of_them_is_a_goal(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "history.db"
    old_database(path)
    with caplog.at_level("WARNING"):
        store = MissionHistory(path)
    assert "kept 1 places and 1 sightings of no known robot" in caplog.text
    assert [(r["id"], r["robot_id"]) for r in store.recent()] == [("m2", None), ("m1", None)]
    assert store.get("m1")["mission"] == "go to the chair"
    assert [(p.name, p.robot_id, p.x, p.y, p.yaw) for p in store.every_place()] == [
        ("desk", None, 1.0, 2.0, 0.5)
    ]
    assert [(s.name, s.robot_id, s.x, s.y) for s in store.every_sighting()] == [
        ("yellow chair", None, -2.0, 3.0)
    ]
    memory = AgentMemory(settings_for(tmp_path), store, robot=RobotId("sim"))
    assert memory.places.all() == {} and memory.sightings.all() == []  # never goals
    notes = [s.note for s in memory.secondhand()]
    assert any("the desk was taught before robots were recorded" in n for n in notes), notes
    # New rows land beside the old ones, with their robot; a second open migrates nothing.
    store.save_place(RobotId("sim"), "desk", 3.0, 3.0, 0.0)
    store.close()
    again = MissionHistory(path)
    assert {(p.robot_id, p.x) for p in again.every_place()} == {(None, 1.0), ("sim", 3.0)}
    assert again._db.execute("PRAGMA user_version").fetchone()[0] == 1
    again.close()


def test_processes_opening_an_old_database_together_migrate_it_once(tmp_path: Path) -> None:
    path = tmp_path / "history.db"
    old_database(path)
    opener = (
        "import sys; sys.path.insert(0, 'src'); from shadowhound.memory import MissionHistory; "
        f"MissionHistory({str(path)!r}).close()"
    )
    root = Path(__file__).parent.parent
    openers = [subprocess.Popen([sys.executable, "-c", opener], cwd=root) for _ in range(3)]
    assert [p.wait(60) for p in openers] == [0, 0, 0]
    store = MissionHistory(path)
    assert len(store.recent()) == 2 and len(store.every_place()) == 1
    assert len(store.every_sighting()) == 1
    store.close()


def test_a_person_claims_what_no_known_robot_made(tmp_path: Path) -> None:
    path = tmp_path / "history.db"
    old_database(path)
    store = MissionHistory(path)
    go2 = RobotId("go2")
    with pytest.raises(ClaimError, match="nothing called 'kitchen'.*desk, yellow chair"):
        store.claim(go2, "kitchen")
    assert store.claim(go2, "desk") == ["place"]
    assert store.claim(go2, "yellow chair") == ["sighting"]
    with pytest.raises(ClaimError, match="nothing called 'desk'.*: nothing"):
        store.claim(RobotId("sim"), "desk")  # claimed already: another robot's now
    assert AgentMemory(settings_for(tmp_path), store, robot=go2).places.all() == {
        "desk": (1.0, 2.0, 0.5)
    }
    assert AgentMemory(settings_for(tmp_path), store, robot=RobotId("sim")).places.all() == {}
    store.close()


def test_a_claim_never_replaces_a_robots_own(tmp_path: Path) -> None:
    path = tmp_path / "history.db"
    old_database(path)
    store = MissionHistory(path)
    store.save_place(RobotId("sim"), "desk", 5.0, 5.0, 0.0)
    with pytest.raises(ClaimError, match="robot 'sim' has a place called 'desk' of its own"):
        store.claim(RobotId("sim"), "desk")
    assert store.load_places(RobotId("sim")) == {"desk": (5.0, 5.0, 0.0)}
    assert {p.robot_id for p in store.every_place()} == {None, "sim"}  # nothing changed
    store.close()


# -- the command line ----------------------------------------------------------------------------


def cli(data: Path, *args: str, **env: str) -> subprocess.CompletedProcess[str]:
    environ = {**os.environ, "SHADOWHOUND_MEMORY__DATA_DIR": str(data), **env}
    environ.pop("SHADOWHOUND_CONFIG", None)
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=environ,
    )


def test_places_lists_other_robots_as_history_and_claims_for_this_robot(tmp_path: Path) -> None:
    old_database(tmp_path / "history.db")
    sim = agent_on(tmp_path, {"type": "sim", "name": "go2"})
    assert sim.execute_mission("walk forward 1 meter, remember this spot as the door").success
    sim.cleanup()
    listed = cli(tmp_path, "places")
    assert listed.returncode == 0, listed.stderr
    lines = listed.stdout.splitlines()
    assert lines[0].startswith("kitchen") and "profile" in lines[0]
    assert "taught to other robots (history, never goals for robot 'sim'):" in lines
    assert any(line.split()[:1] == ["door"] and line.endswith("taught to go2") for line in lines)
    assert any(line.split()[:1] == ["desk"] and "(no known robot)" in line for line in lines)
    rows = json.loads(cli(tmp_path, "places", "--json", "--robot-name", "go2").stdout)
    door = next(r for r in rows if r["name"] == "door")
    assert door["goal"] and door["robot_id"] == "go2"
    desk = next(r for r in rows if r["name"] == "desk")
    assert not desk["goal"] and desk["robot_id"] is None and "claims it" in desk["why"]
    claimed = cli(tmp_path, "places", "--claim", "The Desk", "--robot-name", "go2")
    assert claimed.returncode == 0, claimed.stderr
    assert claimed.stdout.strip() == "claimed the desk (place) for robot 'go2'"
    again = cli(tmp_path, "places", "--claim", "desk")
    assert again.returncode == 1 and "nothing called 'desk' belongs to no known robot" in (
        again.stderr
    )
    bad = cli(tmp_path, "places", "--robot-name", "a b")
    assert bad.returncode == 2 and "--robot-name" in bad.stderr
    history = cli(tmp_path, "history")
    assert any(
        "(no known robot)" in line and "go to the chair" in line
        for line in (history.stdout.splitlines())
    )
    assert "seen by (no known robot)" in history.stdout
