"""Missions about objects (issue 15, item 4): sightings in the world model and in memory, going
to a seen object's standoff, searching for one not seen yet within its budget, the planners'
one namespace of places and objects. Missions run on the real SimRobot and are judged by its
ground truth (true pose, the body never overlapping anything)."""

from __future__ import annotations

import math
import os
import random
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import MemoryConfig, SafetyConfig, SearchConfig, ShadowHoundConfig
from shadowhound.planning.prompts import system_prompt
from shadowhound.planning.rules import RulePlanner
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.robot.sim.scene import DEFAULT_WORLD, World, WorldObject
from shadowhound.robot.sim.sensors import penetration, scene_grid
from shadowhound.skills import default_registry
from shadowhound.world import Belief, KnownObject
from shadowhound.world.image_sighting import Bearing
from shadowhound.world.standoff import PERSON_MARGIN, PERSON_STANDOFF

from .llm_server import ScriptedLLM, json_plan, model_settings

_NO_PLACES = {"places": {}}  # the profile's "charging dock" place would win over the object


def make(world=DEFAULT_WORLD, start=(0.0, 0.0, 0.0), memory=None, **sections):
    cfg = ShadowHoundConfig(**{**_NO_PLACES, **sections})
    if memory is not None:
        cfg = cfg.model_copy(update={"memory": memory})
    robot = SimRobot(cfg.sim, time_scale=0.0, world=world)
    robot.reset(*start)
    return RobotAgent(RobotAgentConfig(robot=robot, settings=cfg)), robot


def never_touched(robot):
    for _t, x, y in robot.true_path:
        depth, what = penetration(robot.world, x, y, robot.config.body_radius)
        assert depth <= 1e-9, f"the body overlapped {what} by {depth:.3f} m at ({x:.2f}, {y:.2f})"


def stands_before(robot, name, gap=None, within=0.05):
    """The true pose is `gap` from the object's surface (the standoff: 0.6 m, a person 1 m and
    the margin), facing its centre."""
    if gap is None:
        gap = PERSON_STANDOFF + PERSON_MARGIN if name == "person" else 0.6
    obj = robot.world.find(name)
    x, y, yaw = robot.true_path[-1][1], robot.true_path[-1][2], robot.get_state().yaw
    assert math.hypot(obj.x - x, obj.y - y) - obj.radius == pytest.approx(gap, abs=within)
    facing = math.atan2(obj.y - y, obj.x - x)
    assert abs(math.remainder(facing - yaw, math.tau)) < math.radians(3)


# -- the world model's sightings ---------------------------------------------------------------


def test_a_sighting_is_remembered_replaced_by_a_newer_one_and_sized_from_the_map():
    belief = Belief(scene_grid(DEFAULT_WORLD))
    ball = belief.sight("The Red  Ball", 3.0, 0.0, stamp=5.0, confidence=0.8)
    assert (ball.name, ball.confidence, ball.stamp) == ("red ball", 0.8, 5.0)
    assert ball.radius == pytest.approx(0.2, abs=0.05)  # the map's blob around the point
    assert belief.sight("red ball", 9.0, 9.0, stamp=4.0).x == 3.0  # an older report: ignored
    assert belief.sight("red ball", 3.1, 0.0, stamp=6.0).x == 3.1
    assert [o.name for o in belief.objects] == ["red ball"]
    assert belief.sight("cup", 0.0, 0.0, stamp=1.0).radius == 0.25  # nothing on the map there
    assert belief.find("the red ball") is belief.find("ball") is belief.objects[0]


@pytest.mark.parametrize(
    "args,words",
    [
        (("", 1.0, 1.0, 0.0), "non-empty name"),
        (("box", math.nan, 1.0, 0.0), "position must be finite"),
        (("box", 1.0, 1.0, 0.0, 1.5), "confidence must be in 0..1"),
        (("box", 1.0, 1.0, math.inf), "stamp must be finite"),
    ],
)
def test_a_bad_sighting_is_refused_saying_why(args, words):
    belief = Belief(scene_grid(DEFAULT_WORLD))
    with pytest.raises(ValueError, match=words):
        belief.sight(*args)
    assert belief.objects == ()


def test_the_simulator_tells_the_map_but_not_the_objects_until_seen():
    agent, robot = make(start=(0.0, 0.0, math.pi))  # facing away from the red ball
    belief = robot.belief()
    assert belief.objects == () and belief.find("red ball") is None
    agent.dry_run("stand up")  # a mission looks before it plans
    seen = {o.name for o in belief.objects}
    assert "charging dock" in seen and "red ball" not in seen  # the camera's field of view


# -- going to a known object -------------------------------------------------------------------


@pytest.mark.parametrize(
    "mission,name",
    [
        ("go to the red ball", "red ball"),
        ("bring me to the fridge", "white fridge"),  # its last word names it
        ("find the blue box", "blue box"),
        ("walk over to the grene plant", "green plant"),  # misspelt
    ],
)
def test_a_seen_object_is_approached_to_its_standoff_facing_it(mission, name):
    agent, robot = make()
    result = agent.execute_mission(mission)
    assert result.success, result.response
    assert "facing it" in result.response
    stands_before(robot, name)
    never_touched(robot)


def test_the_approach_to_a_seen_object_is_checked_before_anything_moves():
    agent, robot = make(safety=SafetyConfig(geofence_radius=4.0))
    result = agent.execute_mission("go to the white fridge")
    assert not result.success and not robot.received_motion
    assert "geofence of 4 m" in result.response


def test_dry_run_predicts_the_standoff_path_facing_the_object():
    agent, robot = make()
    result = agent.dry_run("go to the red ball")
    assert result.success and not robot.received_motion
    end = result.predicted_path[-1]
    assert (end.x, end.y) == (pytest.approx(2.2, abs=0.03), pytest.approx(0.0, abs=0.01))
    assert end.yaw == pytest.approx(0.0, abs=1e-6)


# -- searching for an object not seen yet ---------------------------------------------------------


@pytest.mark.parametrize(
    "mission,name,after",
    [
        ("go to the person and say hello", "person", "hello"),
        ("walk to the charging dock and sit down", "charging dock", None),
        ("look for the yellow chair", "yellow chair", None),
    ],
)
def test_an_object_out_of_view_is_searched_for_then_approached(mission, name, after):
    agent, robot = make()
    assert robot.belief().find(name) is None
    result = agent.execute_mission(mission)
    assert result.success, result.response
    assert f"found the {name}" in result.response
    stands_before(robot, name)
    never_touched(robot)
    if after == "hello":
        assert any(c.kind == "trick" and c.value == "hello" and c.accepted for c in robot.commands)
    if "sit" in mission:
        assert robot.get_state().posture.value == "sitting"


def test_an_object_hidden_behind_a_wall_is_found_by_walking_round_it():
    # A wall of posts across the room with a gap at the top; the box stands behind it, out of
    # sight from the start whichever way the robot turns.
    posts = tuple(
        WorldObject(f"post {i}", 1.0, -3.75 + 0.4 * i, 0.25, height=2.0) for i in range(16)
    )
    world = World(objects=(*posts, WorldObject("blue box", 3.0, -2.0, 0.3)), bounds=(-4, 5, -4, 4))
    agent, robot = make(world=world, start=(-2.0, -1.0, 0.0))
    result = agent.execute_mission("find the blue box")
    assert result.success, result.response
    assert "found the blue box" in result.response and "1 look(s)" not in result.response
    stands_before(robot, "blue box")
    never_touched(robot)


def test_a_search_that_finds_nothing_says_where_it_looked():
    # A unicorn the simulator can label, standing behind the room's wall: never in view.
    hidden = World(objects=(*DEFAULT_WORLD.objects, WorldObject("unicorn", 7.5, 0.0, 0.3)))
    agent, robot = make(world=hidden, search=SearchConfig(max_seconds=60, max_distance=5))
    result = agent.execute_mission("find the unicorn")
    assert not result.success
    assert "did not find the unicorn: looked around from (0.0, 0.0)" in result.response
    assert "search.max_seconds" in result.response
    assert robot.true_odometer <= 5 + 0.05
    never_touched(robot)


class SeesInDirections(SimRobot):
    """A simulated robot whose detector also saw things in a direction only (a 2-D box with no
    range, as the Go2's BoxIntake keeps them)."""

    def bearings(self) -> tuple[Bearing, ...]:
        return (
            Bearing("unicorn", 0.0, 0.0, 0.0, 0.9, 1.0, "no scan at the image's time"),
            Bearing("red ball", 0.0, 0.0, 0.0, 0.9, 2.0, "9.0 m away, beyond 6 m"),
        )


def test_a_search_that_saw_the_thing_only_in_a_direction_says_so():
    """Issue 24: a box with no range is a direction, never a goal; a search that had only that
    ends without it, and says why."""
    hidden = World(objects=(*DEFAULT_WORLD.objects, WorldObject("unicorn", 7.5, 0.0, 0.3)))
    cfg = ShadowHoundConfig(**_NO_PLACES, search=SearchConfig(max_seconds=60, max_distance=2))
    robot = SeesInDirections(cfg.sim, time_scale=0.0, world=hidden)
    result = RobotAgent(RobotAgentConfig(robot=robot, settings=cfg)).execute_mission(
        "find the unicorn"
    )
    assert not result.success
    assert (
        "The unicorn was seen only in a direction (0 degrees from (0.0, 0.0)), at no known "
        "distance (no scan at the image's time): a direction is never a place to go."
    ) in result.response, result.response
    assert "red ball was seen only" not in result.response
    assert robot.true_odometer <= 2 + 0.05


def test_a_name_the_robot_cannot_recognise_is_refused_before_moving():
    """A typo or a place nobody taught ("the bedroom") starts no search: refused at once,
    naming the word, what is known and what could be looked for."""
    agent, robot = make()
    for mission in ("go to the bedroom", "find the zorblax", "walk over to the sofa"):
        result = agent.execute_mission(mission)
        assert not result.success and not robot.received_motion, result.response
        word = mission.split()[-1]
        assert f"'{word}' is not a place or an object I know" in result.response
        assert "I can look for: blue box, charging dock, green plant, person" in result.response
    near = agent.execute_mission("go to the charging station")
    assert "Did you mean the charging dock?" in near.response
    dry = agent.dry_run("go to the bedroom")
    assert not dry.success and "'bedroom' is not a place" in dry.response


def test_a_shorter_name_finds_the_one_object_it_fits_and_asks_between_two():
    """ "the chair" is the yellow chair, seen or looked for; with two chairs known it asks."""
    agent, robot = make()
    result = agent.execute_mission("go to the chair")  # not in view at the start: a search
    assert result.success, result.response
    assert "found the yellow chair" in result.response
    stands_before(robot, "yellow chair")
    two = World(objects=(*DEFAULT_WORLD.objects, WorldObject("red chair", 2.0, -2.0, 0.4)))
    agent, robot = make(world=two)
    assert agent.execute_mission("turn left 120 degrees").success  # sees the yellow chair
    assert agent.execute_mission("turn right 200 degrees").success  # and the red one
    asked = agent.execute_mission("go to the chair")
    assert not asked.success, asked.response
    assert "'chair' could be the" in asked.response and "say which" in asked.response
    assert "the yellow chair" in asked.response and "the red chair" in asked.response


def test_a_dry_run_of_a_search_says_so_with_its_budget():
    agent, robot = make(search=SearchConfig(max_seconds=90, max_distance=12))
    dry = agent.dry_run("find the chair")
    assert dry.success and not robot.received_motion
    assert (
        "step 1 (nav.goto): would look for the chair (not seen yet) for up to 90 s and 12 m"
        in dry.response
    )
    assert "end near" not in dry.response  # where a search ends is not known


def test_without_a_map_an_unknown_name_is_refused_before_moving():
    cfg = ShadowHoundConfig(**_NO_PLACES)
    cfg = cfg.model_copy(update={"sim": cfg.sim.model_copy(update={"collisions": False})})
    robot = SimRobot(cfg.sim, time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=cfg))
    result = agent.execute_mission("go to the unicorn")
    assert not result.success and not robot.received_motion
    assert "'unicorn' is not a place or an object I know. Places: start, home." in (result.response)


def _fences():
    circle = st.floats(2.5, 6.0)
    polygon = st.sampled_from(
        [None, [(-3, -3), (3, -3), (3, 3), (-3, 3)], [(-1, -2), (4, -2), (4, 2), (-1, 2)]]
    )
    return st.tuples(circle, polygon)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000), fence=_fences(), seconds=st.floats(15, 60), metres=st.floats(1, 8)
)
def test_a_search_never_leaves_the_geofence_nor_exceeds_its_budget(seed, fence, seconds, metres):
    rng = random.Random(seed)
    objects = tuple(
        WorldObject(f"thing {i}", rng.uniform(-4, 4), rng.uniform(-3, 3), rng.uniform(0.1, 0.5))
        for i in range(rng.randint(0, 6))
    )
    objects = tuple(o for o in objects if math.hypot(o.x, o.y) > o.radius + 0.5)
    world = World(objects=objects, bounds=(-5, 5, -4, 4))
    radius, polygon = fence
    safety = SafetyConfig(geofence_radius=radius, geofence_polygon=polygon)
    agent, robot = make(
        world=world, safety=safety, search=SearchConfig(max_seconds=seconds, max_distance=metres)
    )
    began = robot.now()
    result = agent.execute_mission("find the unicorn")  # not in the scene: the whole budget
    assert not result.success
    assert robot.true_odometer <= metres + 0.05, result.response
    assert robot.now() - began <= seconds + 0.5, result.response  # one tick and a stop
    margin = safety.geofence_margin
    for _t, x, y in robot.true_path:
        assert math.hypot(x, y) <= radius - margin + 0.01, (x, y, result.response)
        if polygon:
            xs, ys = [p[0] for p in polygon], [p[1] for p in polygon]
            assert min(xs) + margin - 0.01 <= x <= max(xs) - margin + 0.01
            assert min(ys) + margin - 0.01 <= y <= max(ys) - margin + 0.01
    never_touched(robot)


# -- memory: sightings outlive the mission and the process -----------------------------------------


def test_sightings_are_kept_in_memory_for_later_missions_and_history(tmp_path):
    memory = MemoryConfig(enabled=True, data_dir=str(tmp_path))
    agent, robot = make(memory=memory)
    assert agent.execute_mission("turn left 120 degrees").success  # sees the chair
    agent.cleanup()
    # A new process: a fresh robot and agent, facing away from the chair again.
    agent, robot = make(memory=memory)
    assert robot.belief().find("yellow chair") is None
    planned = agent.dry_run("go to the yellow chair")
    assert planned.success and len(planned.predicted_path) > 1  # a known object: a real path
    chair = robot.world.find("yellow chair")
    end = planned.predicted_path[-1]
    assert math.hypot(chair.x - end.x, chair.y - end.y) == pytest.approx(0.4 + 0.6, abs=0.05)
    agent.cleanup()
    env = {**os.environ, "SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path)}
    env.pop("SHADOWHOUND_CONFIG", None)
    shown = subprocess.run(
        [sys.executable, "-m", "shadowhound", "history"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert shown.returncode == 0, shown.stderr
    assert "objects seen" in shown.stdout and "yellow chair" in shown.stdout


# -- the planners: one namespace of places and objects ---------------------------------------------

# Held out: sentences of each kind that no rule was written from.
HELD_OUT = [
    ("please find the green plant", ["nav.goto"], "green plant"),
    ("could you locate my keys", ["nav.goto"], "keys"),
    ("search for the person then sit", ["nav.goto", "body.sit"], "person"),
    ("take us to the white fridge", ["nav.goto"], "white fridge"),
    ("guide me to the door and wave", ["nav.goto", "body.sport"], "door"),
    ("head over to the blue box and lie down", ["nav.goto", "body.lie_down"], "blue box"),
    ("approach the red ball", ["nav.goto"], "red ball"),
    ("go find the charging dock", ["nav.goto"], "charging dock"),
    ("loook for the yellow chair", ["nav.goto"], "yellow chair"),  # misspelt verb
    ("track down the cat", ["nav.goto"], "cat"),
]


@pytest.mark.parametrize("text,skills,place", HELD_OUT)
def test_the_offline_planner_reads_requests_about_things(text, skills, place):
    plan = RulePlanner().plan(text)
    assert [s.skill for s in plan.steps] == skills
    assert plan.steps[0].args == {"place": place}


def test_the_model_is_told_the_objects_seen_after_the_stable_prefix():
    prompt = system_prompt(
        default_registry(),
        style="plan",
        places={"kitchen": (4.0, 2.5)},
        objects={"red ball": (3.0, 0.0)},
    )
    assert "Objects seen: red ball (3.0, 0.0)." in prompt
    assert prompt.index("Rules:") < prompt.index("Places:") < prompt.index("Objects seen:")
    assert "nav.goto with its name as place" in prompt


def test_an_llm_planned_mission_gets_the_objects_and_goes_to_one():
    from shadowhound.config import load_config

    with ScriptedLLM(models=("test-model",)) as srv:
        srv.script(json_plan([{"skill": "nav.goto", "args": {"place": "red ball"}}]))
        cfg = load_config(
            "llamacpp",
            {
                "llm": model_settings(srv),
                **_NO_PLACES,
            },
            environ={},
        )
        robot = SimRobot(time_scale=0.0)
        agent = RobotAgent(RobotAgentConfig(robot=robot, settings=cfg))
        result = agent.execute_mission("walk up to that ball")
        system = srv.requests[0]["messages"][0]["content"]
    assert "Objects seen:" in system and "red ball (3.0, 0.0)" in system
    assert result.success, result.response
    stands_before(robot, "red ball")


def test_known_objects_from_memory_are_marked_remembered_and_replaced_by_a_fresh_sighting():
    belief = Belief(scene_grid(DEFAULT_WORLD))
    belief.remember(KnownObject("red ball", 3.0, 0.0, 0.2, 1.0, stamp=500.0))
    assert belief.objects[0].remembered
    assert belief.sight("red ball", 3.05, 0.0, stamp=1.0).x == 3.05  # another run's clock


def test_an_object_found_by_a_search_is_approached_only_on_a_path_the_governor_passes():
    # The dock is behind the robot and outside the geofence: the search sees it, the approach
    # to its standoff is refused, and the robot never leaves the fence.
    world = World(objects=(WorldObject("charging dock", -3.6, 0.0, 0.3),), bounds=(-5, 5, -5, 5))
    agent, robot = make(world=world, safety=SafetyConfig(geofence_radius=2.5))
    result = agent.execute_mission("go to the charging dock")
    assert not result.success
    assert "the path to the charging dock is refused" in result.response
    assert "geofence of 2.5 m" in result.response
    assert all(math.hypot(x, y) <= 2.5 for _t, x, y in robot.true_path)


def test_a_name_that_fits_two_objects_seen_is_refused_asking_which():
    world = World(
        objects=(WorldObject("red ball", 2.0, 0.5, 0.2), WorldObject("blue ball", 2.0, -0.5, 0.2)),
        bounds=(-4, 4, -4, 4),
    )
    agent, robot = make(world=world)
    result = agent.execute_mission("go to the ball")
    assert not result.success and not robot.received_motion
    assert "'ball' could be the" in result.response and "say which" in result.response
    assert agent.execute_mission("go to the blue ball").success
    stands_before(robot, "blue ball")
