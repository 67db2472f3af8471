"""Places and goals are finite at every entry (issue 21: odometry that lies).

A Go2's odometry can report NaN or infinite poses. "Remember this spot as the den" at x = NaN
used to succeed; the history insert then failed NOT NULL and blocked every later record, and
"go to the den" with a map crashed the governor inside grid.cell_of. Here the robot is a real
SimRobot whose pose, as the agent reads it, lies (tests/lying_odometry.py).
"""

from __future__ import annotations

import logging
import math
import sqlite3
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot, load_config
from shadowhound import events as ev
from shadowhound.checking import check_plan
from shadowhound.errors import ConfigError, PlaceError, ShadowHoundError
from shadowhound.memory import MissionHistory, PlaceBook, RobotId, known_places
from shadowhound.plan import Plan, SkillCall
from shadowhound.safety import Governor
from shadowhound.skills import PlanEnv, default_registry
from shadowhound.state import Pose2D, RobotState
from tests.lying_odometry import LyingOdometry

SIM = RobotId("sim")

UNKNOWN_HERE = (
    "the robot's position is unknown (odometry reports x=nan): cannot remember a place there"
)


def lying_agent(data: Path, **lies: float) -> tuple[RobotAgent, LyingOdometry]:
    robot = LyingOdometry(**lies)
    settings = load_config(
        "offline", {"memory": {"enabled": True, "data_dir": str(data)}}, environ={}
    )
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    agent.initialize()
    return agent, robot


def test_a_place_is_not_remembered_where_the_odometry_lies_and_no_record_is_lost(tmp_path):
    agent, robot = lying_agent(tmp_path, x=math.nan)
    try:
        refused = agent.execute_mission("remember this spot as the den")
        assert not refused.success
        assert UNKNOWN_HERE in refused.response  # refused at the plan check, before it runs
        assert "den" not in agent.memory.places.all()
        robot.lies = {}  # the odometry is back
        walked = agent.execute_mission("walk forward 1 meter")
        assert walked.success, walked.response
        assert agent.memory.history.unsaved == 0
        missions = [r["mission"] for r in agent.recent_missions(5)]
        assert missions == ["walk forward 1 meter", "remember this spot as the den"]
    finally:
        agent.cleanup()


def test_odometry_that_goes_bad_during_the_mission_is_refused_by_the_skill(tmp_path):
    """The plan was checked on a good pose; the skill reads the pose again when it runs."""
    agent, robot = lying_agent(tmp_path)
    robot.lies = {}

    def odometry_fails(event: ev.MissionEvent) -> None:
        if isinstance(event, ev.StepStarted):
            robot.lies = {"x": math.nan}

    agent.add_listener(odometry_fails)
    try:
        result = agent.execute_mission("remember this spot as the den")
        assert not result.success
        assert UNKNOWN_HERE in result.response
        assert "den" not in agent.memory.places.all()
        assert agent.memory.history.unsaved == 0
    finally:
        agent.cleanup()


def test_a_place_book_refuses_a_position_that_is_not_finite():
    book = PlaceBook(robot=SIM)
    for x, y, yaw in [(math.nan, 0.0, 0.0), (0.0, math.inf, 0.0), (0.0, 0.0, -math.inf)]:
        with pytest.raises(PlaceError, match=r"not finite \((x|y|yaw)=.*\); a place needs finite"):
            book.remember("den", x, y, yaw)
    with pytest.raises(PlaceError, match="needs a name"):
        book.remember("  ", 1.0, 1.0, 0.0)
    assert book.all() == {}


def test_a_bad_place_row_in_the_database_is_skipped_with_a_warning(tmp_path, caplog):
    path = tmp_path / "history.db"
    MissionHistory(path).close()
    with sqlite3.connect(path) as db:  # a row written by an older version, or by hand
        db.execute("INSERT INTO places VALUES ('sim', 'den', ?, 1.0, 0.0, 0.0)", (math.inf,))
        db.execute("INSERT INTO places VALUES ('sim', 'hall', 'by the door', 1.0, 0.0, 0.0)")
        db.execute("INSERT INTO places VALUES ('sim', 'desk', 2.0, 1.0, 0.0, 0.0)")
        db.execute(
            "INSERT INTO sightings VALUES ('sim', 'ball', 1.0, ?, 0.1, 1.0, 0.0, 0.0)",
            (-math.inf,),
        )
    store = MissionHistory(path)
    with caplog.at_level(logging.WARNING):
        book = PlaceBook(store, robot=SIM)
    assert book.all() == {"desk": (2.0, 1.0, 0.0)}
    assert "skipped the taught place 'den'" in caplog.text and "x=inf" in caplog.text
    assert "skipped the taught place 'hall'" in caplog.text
    from shadowhound.memory.sightings import SightingBook

    with caplog.at_level(logging.WARNING):
        assert SightingBook(store, robot=SIM).all() == []
    assert "skipped the sighting of 'ball'" in caplog.text
    store.close()


@pytest.mark.parametrize("bad", ["nan", "inf", math.nan, -math.inf, [1.0], None, True])
def test_a_profile_place_that_is_not_finite_is_a_configuration_error(bad):
    with pytest.raises(ConfigError, match=r"places.*(finite|pair)"):
        load_config("offline", {"places": {"den": [bad, 1.0]}}, environ={})


@pytest.mark.parametrize("bad", ["nan", "inf", "-Infinity", math.nan, math.inf])
def test_goto_coordinates_that_are_not_finite_are_refused_with_what_is_allowed(bad):
    settings = ShadowHoundConfig()
    start = RobotState()
    plan = Plan([SkillCall("nav.goto", {"x": bad, "y": 1.0})])
    checked = check_plan(
        plan, default_registry(), Governor(settings.safety), settings, PlanEnv(settings), start
    )
    assert checked.problems and not checked.calls
    assert "is not a finite number; give a number of metres" in checked.problems[0]


def test_going_to_a_place_with_a_map_from_a_lying_pose_is_a_refusal_not_a_crash(tmp_path):
    agent, robot = lying_agent(tmp_path, x=math.nan)
    try:
        robot.lies = {}
        assert agent.execute_mission("remember this spot as the den").success
        robot.lies = {"x": math.nan}
        went = agent.execute_mission("go to the den")
        assert not went.success and went.refusals
        assert "the robot's position is unknown (odometry reports x=nan)" in went.response
        assert "internal error" not in went.response
    finally:
        agent.cleanup()


# -- any coordinates: a plan, or a refusal; never another exception ------------------------

SETTINGS = ShadowHoundConfig()
BELIEF = SimRobot(SETTINGS.sim, time_scale=0.0).belief()  # the simulator's map
REGISTRY = default_registry()
GOVERNOR = Governor(SETTINGS.safety)
coordinate = st.one_of(
    st.floats(-12, 12),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308]),
)
entries = st.sampled_from(["goto x y", "taught place", "profile place", "start"])


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


@settings(max_examples=80, deadline=None)
@given(
    x=coordinate,
    y=coordinate,
    start=st.tuples(coordinate, coordinate, st.one_of(st.floats(-4, 4), coordinate)),
    entry=entries,
    mapped=st.booleans(),
)
def test_any_coordinates_either_plan_or_are_refused_clearly(x, y, start, entry, mapped):
    """Wherever a goal enters (x and y, a taught place, a profile place, the mission's start),
    and wherever odometry puts the robot, checking the plan never raises: it passes, or says
    why not. A goal or a start that is not finite never passes."""
    settings = SETTINGS
    book = PlaceBook(robot=SIM)
    try:
        if entry == "taught place":
            book.remember("den", x, y, 0.0)
        elif entry == "profile place":
            settings = load_config("offline", {"places": {"den": [x, y]}}, environ={})
    except ShadowHoundError as exc:  # PlaceError, ConfigError: refused at the door
        assert not _finite(x, y) and str(exc)
        return
    args = {"x": x, "y": y} if entry == "goto x y" else {"place": "den"}
    if entry == "start":
        args = {"place": "start"}
    robot = RobotState(x=start[0], y=start[1], yaw=start[2])
    places = {n: p.position for n, p in known_places(settings.places, book).items()}
    env = PlanEnv(settings, robot.pose, places, belief=BELIEF if mapped else None)
    plan = Plan([SkillCall("nav.goto", args)])
    checked = check_plan(plan, REGISTRY, GOVERNOR, settings, env, robot)
    goal_known = entry == "start" or _finite(x, y)
    if not (goal_known and robot.pose.unknown() == ""):
        assert checked.problems, "a goal or a start that is not finite passed the checks"
    assert all(isinstance(p, str) and p for p in checked.problems)


def test_the_governor_refuses_a_path_it_cannot_check():
    """A step from a pose that is not finite: the limits, the geofence and the map cannot be
    checked, so it is refused (NaN compares false with every limit and would pass them)."""
    env = PlanEnv(SETTINGS, belief=BELIEF)
    for pose in (Pose2D(math.nan, 0.0, 0.0), Pose2D(0.0, 0.0, math.inf)):
        start = RobotState(x=pose.x, y=pose.y, yaw=pose.yaw)
        plan = Plan([SkillCall("nav.move", {"distance": 1.0})])
        checked = check_plan(plan, REGISTRY, GOVERNOR, SETTINGS, env, start)
        assert checked.problems == [
            f"step 1 (nav.move): the robot's position is unknown (odometry reports "
            f"{pose.unknown()}): a step that moves the robot cannot be checked against the "
            "limits, the geofence and the map from there"
        ]
