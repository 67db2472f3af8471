"""Navigation on the robot's map: planned paths around obstacles, straight legs checked against
the map, re-plans when the map was wrong, and the body never touching anything.

The simulator's default scene: a red ball at (3, 0), a blue box at (2.5, 2), walls at +-6 m.
"""

import math
import threading

from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from shadowhound import (
    RobotAgent,
    RobotAgentConfig,
    ShadowHoundConfig,
    SimRobot,
    SkillCall,
    default_registry,
)
from shadowhound.robot.sim.scene import DEFAULT_WORLD, World, WorldObject
from shadowhound.robot.sim.sensors import penetration
from shadowhound.skills import PlanEnv, SkillContext
from shadowhound.skills.context import robot_belief

BODY = 0.35


def make(world=DEFAULT_WORLD, map_world=None, start=(0.0, 0.0, 0.0), **safety):
    robot = SimRobot(time_scale=0.0, world=world, map_world=map_world)
    robot.reset(*start)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=ShadowHoundConfig(safety=safety)))
    agent.initialize()
    return agent, robot


def deepest(robot):
    """How far the body ever overlapped the scene (0.0: never touched anything)."""
    return max(penetration(robot.world, x, y, BODY)[0] for _t, x, y in robot.true_path)


def walked(robot):
    points = robot.true_path
    return sum(math.dist(a[1:], b[1:]) for a, b in zip(points, points[1:], strict=False))


def test_a_straight_move_into_the_red_ball_is_refused_naming_it_and_the_distance():
    agent, robot = make()
    result = agent.execute_mission("go forward 4 meters")
    assert not result.success and not robot.received_motion
    assert "nav.move 4 m: the red ball is in the way at 2.4 m" in result.response


def test_a_sidestep_into_the_wall_is_refused_naming_the_wall():
    agent, robot = make()
    result = agent.execute_mission("step to the left 6 meters")
    assert not result.success and not robot.received_motion
    assert "nav.strafe 6 m: the wall is in the way at 5.6 m" in result.response


def test_going_to_a_point_behind_the_red_ball_walks_around_it():
    agent, robot = make()
    result = agent.execute_mission("go to x=4, y=0")
    assert result.success, result.response
    st_ = robot.get_state()
    assert math.hypot(st_.x - 4.0, st_.y) < 0.01
    assert deepest(robot) == 0.0
    # Around the ball, not through it: longer than the line, within 15 % of it.
    assert 4.0 < walked(robot) < 4.0 * 1.15
    assert min(abs(y) for _t, x, y in robot.true_path if abs(x - 3.0) < 0.05) > 0.2 + BODY


def test_a_goal_inside_an_objects_clearance_ends_at_the_nearest_clear_point_facing_it():
    """(3, 2) is 0.5 m from the blue box's centre: the body would overlap it there. As Nav2's
    planner tolerance does, the walk ends at the nearest point that keeps the body clear (within
    0.5 m), facing the goal, and says so."""
    agent, robot = make()
    result = agent.execute_mission("go to position 3, 2")
    assert result.success, result.response
    st_ = robot.get_state()
    assert 0.15 < math.hypot(st_.x - 3.0, st_.y - 2.0) < 0.5, (st_.x, st_.y)
    facing = math.atan2(2.0 - st_.y, 3.0 - st_.x)
    assert abs(math.remainder(st_.yaw - facing, math.tau)) < math.radians(3)
    assert deepest(robot) == 0.0
    assert (
        "the point (3.00, 2.00) lies within the blue box's clearance: went to the nearest "
        "point that keeps the body clear"
    ) in result.response
    dry = agent.dry_run("go to position 3, 2")  # the plan check predicts the same end
    assert (
        dry.success
        and math.hypot(dry.predicted_path[-1].x - st_.x, dry.predicted_path[-1].y - st_.y) < 0.05
    )


def test_a_goal_deep_inside_an_objects_clearance_is_refused_naming_it():
    agent, robot = make()
    result = agent.execute_mission("go to position 2.5, 2")  # the blue box's centre
    assert not result.success and not robot.received_motion
    assert (
        "the goal (2.50, 2.00) is inside the blue box's clearance (0.35 m kept for the body)"
    ) in result.response


def test_a_goal_nothing_can_reach_is_refused_with_the_planners_reason():
    ring = World(
        objects=tuple(
            WorldObject(f"post {i}", 3 + 1.2 * math.cos(a), 1.2 * math.sin(a), radius=0.3)
            for i, a in enumerate(k * math.pi / 6 for k in range(12))
        )
    )
    agent, robot = make(world=ring)
    result = agent.execute_mission("go to position 3, 0")
    assert not result.success and not robot.received_motion
    assert "no safe path to (3.00, 0.00): no collision-free path" in result.response


def test_a_stale_map_stops_the_walk_at_contact_then_it_replans_from_a_scan():
    """The map was made before the ball was put there: the planned line runs into it. The body
    stops at contact, the map is updated from a scan, and a new path goes around."""
    stale = World(objects=tuple(o for o in DEFAULT_WORLD.objects if o.name != "red ball"))
    agent, robot = make(map_world=stale)
    result = agent.execute_mission("go to x=4, y=0")
    assert result.success, result.response
    st_ = robot.get_state()
    assert math.hypot(st_.x - 4.0, st_.y) < 0.05
    assert "blocked by the red ball" in result.steps[0].output
    assert "re-planned from a fresh scan" in result.steps[0].output
    assert deepest(robot) == 0.0


def test_without_a_map_goto_walks_straight_as_before():
    robot = SimRobot(time_scale=0.0, world=World(objects=()))
    assert robot_belief(robot) is not None  # an empty room is still a map
    ghost = SimRobot(SimRobot().config.model_copy(update={"collisions": False}), time_scale=0.0)
    assert robot_belief(ghost) is None
    agent = RobotAgent(RobotAgentConfig(robot=ghost))
    result = agent.dry_run("go to x=4, y=0")
    assert [(p.x, p.y) for p in result.predicted_path] == [(0.0, 0.0), (4.0, 0.0)]


def test_the_step_limit_applies_to_each_straight_leg_of_a_planned_path():
    agent, _robot = make(max_step_distance=2.0)
    result = agent.dry_run("go to x=4, y=0")  # about 4.5 m in three legs, each under 3 m
    assert not result.success and "a straight leg of 2.7" in result.response
    agent, _robot = make(max_step_distance=3.0)
    assert agent.dry_run("go to x=4, y=0").success


def test_a_planned_detour_counts_in_full_against_the_mission_distance():
    agent, _robot = make(max_mission_distance=4.3)  # the line is 4 m, the path about 4.5
    result = agent.dry_run("go to x=4, y=0")
    assert not result.success and "the mission would travel 4.5 m" in result.response


# -- the property: no mission makes the body touch anything ------------------------------------


def _scenes():
    obj = st.builds(
        lambda i, x, y, r: WorldObject(f"thing {i}", x, y, radius=r),
        st.integers(0, 999),
        st.floats(-5, 5),
        st.floats(-5, 5),
        st.floats(0.1, 0.6),
    )
    return st.lists(obj, max_size=6, unique_by=lambda o: o.name).map(
        lambda objs: World(objects=tuple(objs))
    )


_length = st.floats(-5, 5).map(lambda v: round(v, 2))
_calls = st.one_of(
    st.builds(lambda d: SkillCall("nav.move", {"distance": d}), _length),
    st.builds(lambda d: SkillCall("nav.strafe", {"distance": d}), _length),
    st.builds(lambda a: SkillCall("nav.rotate", {"degrees": a}), st.integers(-180, 180)),
    st.builds(lambda x, y: SkillCall("nav.goto", {"x": x, "y": y}), _length, _length),
    st.just(SkillCall("nav.patrol", {})),
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    world=_scenes(),
    start=st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-math.pi, math.pi)),
    calls=st.lists(_calls, min_size=1, max_size=4),
)
def test_random_plans_in_random_scenes_never_touch_anything(world, start, calls):
    if penetration(world, start[0], start[1], BODY)[0] > 0:
        return  # a start inside something is not a pose the robot can be in
    agent, robot = make(world=world, start=start, geofence_radius=20.0)
    result = agent.run_plan(calls)
    event(
        f"moved, {'succeeded' if result.success else 'failed'}"
        if robot.received_motion
        else "refused before moving"
    )
    assert robot.true_path_complete
    assert deepest(robot) == 0.0, result.response
    assert "blocked by" not in result.response  # the map was true: no contact at all
    agent.cleanup()


PUBLIC = [
    "walk forward three meters",
    "walk in a square with 1 meter sides",
    "patrol the perimeter",
    "go to position 2, 1",
    "go to the kitchen",
    "go to x=4, y=0",
    "walk forward 2 meters, turn left 90 degrees, then walk forward 3 meters",
    "move forward 4 meters",
    "walk a square with sides of 2 meters",
    "come back",
]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    mission=st.sampled_from(PUBLIC),
    world=_scenes(),
    start=st.tuples(st.floats(-4, 4), st.floats(-4, 4), st.floats(-math.pi, math.pi)),
)
def test_public_missions_in_random_scenes_never_touch_anything(mission, world, start):
    scene = World(objects=DEFAULT_WORLD.objects + world.objects) if start[0] > 0 else world
    if penetration(scene, start[0], start[1], BODY)[0] > 0:
        return
    agent, robot = make(world=scene, start=start)
    result = agent.execute_mission(mission)
    event(
        f"moved, {'succeeded' if result.success else 'failed'}"
        if robot.received_motion
        else "refused before moving"
    )
    assert deepest(robot) == 0.0, result.response
    assert "blocked by" not in result.response
    agent.cleanup()


def test_goto_progress_is_the_distance_along_the_planned_path():
    robot = SimRobot(time_scale=0.0)
    settings = ShadowHoundConfig()
    env = PlanEnv(settings, robot.get_state().pose, belief=robot_belief(robot))
    seen = []
    ctx = SkillContext(robot, env, threading.Event(), on_progress=seen.append)
    call = default_registry().validate(SkillCall("nav.goto", {"x": 4.0, "y": 0.0}))
    corners = call.skill.predict(robot.get_state().pose, call.args, env)
    assert len(corners) >= 2  # a detour: corners before the goal
    ctx.start_clock(call.skill.timeout_for(call.args, env))
    call.skill.run(ctx, call.args)
    assert seen == sorted(seen) and seen[-1] == 1.0  # never backwards, ends complete
    first = math.hypot(corners[0].x, corners[0].y)
    legs = zip(corners, corners[1:], strict=False)
    total = first + sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in legs)
    # While turning at the first corner progress holds at the first leg's share of the path.
    assert any(abs(f - first / total) < 1e-9 for f in seen)


def test_a_path_re_planned_on_the_way_is_checked_by_the_governors_rules():
    """The stale map hid the ball; the detour round it would leave the narrow geofence, so the
    walk stops where it is instead of taking a path no plan check has seen."""
    stale = World(objects=tuple(o for o in DEFAULT_WORLD.objects if o.name != "red ball"))
    corridor = [(-1.0, -0.6), (5.0, -0.6), (5.0, 0.6), (-1.0, 0.6)]
    agent, robot = make(map_world=stale, geofence_polygon=corridor)
    result = agent.execute_mission("go to x=4, y=0")
    assert not result.success
    assert "re-planned, but the new path is refused" in result.response
    assert "geofence polygon" in result.response
    assert robot.get_state().x < 2.5 and deepest(robot) < 1e-9  # touched (stale map), no more


def test_doctor_lists_the_places_the_body_cannot_reach(tmp_path):
    """Places are checked against the simulator's map from the origin: one inside an object's
    clearance but near a clear point is reached there; one deep inside is listed, saying why."""
    from tests.test_cli import shadowhound

    profile = tmp_path / "places.yaml"
    profile.write_text(
        "places:\n  kitchen: [4.0, 2.5]\n  by the box: [3.0, 2.0]\n  in the ball: [3.0, 0.0]\n"
    )
    done = shadowhound("--config", str(profile), "doctor")
    assert done.returncode == 0, done.stderr
    assert "ok  places reachable on the simulator's map: kitchen, by the box" in done.stdout
    assert (
        "warn place 'in the ball' (3.0, 0.0) cannot be reached: the goal (3.00, 0.00) is "
        "inside the red ball's clearance"
    ) in done.stdout


def test_the_profiles_charging_dock_is_reached_beside_the_dock():
    """The default profile's place stands clear of the dock (it once lay inside its clearance,
    and "go to the charging dock" was refused)."""
    agent, robot = make()  # the default profile's places
    result = agent.execute_mission("go to the charging dock")
    assert result.success, result.response
    st_ = robot.get_state()
    dock = DEFAULT_WORLD.find("charging dock")
    assert dock is not None and deepest(robot) == 0.0
    assert math.hypot(st_.x - dock.x, st_.y - dock.y) < dock.radius + 0.6 + 0.1
    assert "lies within" not in result.response  # the place itself is clear: no detour
