"""Watches on steps (issue 26): "until", "unless", "stop if", evaluated by the runtime at control
rate over what the robot observes, judged by the simulator's truth (its true pose and its
scene's camera truth, `scene.visible_objects`), never by the robot's own readings."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig
from shadowhound.plan import Plan, PlanningError, SkillCall, Watch
from shadowhound.planning import FixedPlanner
from shadowhound.planning.rules import RulePlanner
from shadowhound.result import MissionStatus, StepStatus
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.robot.sim.scene import World, WorldObject, visible_objects
from shadowhound.skills.watches import Watcher, _Reading
from shadowhound.state import Pose2D, RobotState, Scan, Sighting
from tests.robot.test_base import Minimal

BALL = WorldObject("red ball", 4.5, 1.5, 0.15, height=0.3, color=(220, 30, 30))
PILLAR = WorldObject("pillar", 2.0, 1.0, 0.45, height=1.5)  # hides the ball at first
PERSON = WorldObject("person", 3.2, 0.0, 0.25, height=1.7, color=(60, 90, 200))


class ScriptedRobot(SimRobot):
    """The simulator whose scene changes during the run: `later` enters the scene (or moves
    there, when one of its name is in it) once the body has passed `at_x` (a person steps into
    the path). Its truth: `path`, every true pose the control loop let pass."""

    def __init__(self, world: World, later: WorldObject | None = None, at_x: float = 0.0):
        super().__init__(time_scale=0, world=world)
        self.later, self.at_x = later, at_x
        self.path: list[RobotState] = []

    def sleep(self, seconds: float) -> None:
        super().sleep(seconds)
        truth = self.get_state()
        self.path.append(truth)
        if self.later is not None and truth.x >= self.at_x:
            others = tuple(o for o in self.world.objects if o.name != self.later.name)
            self.set_world(World(objects=(*others, self.later)))
            self.later = None


def agent_on(robot: object, planner: object | None = None) -> RobotAgent:
    settings = ShadowHoundConfig()
    settings.memory.enabled = False
    return RobotAgent(
        RobotAgentConfig(robot=robot, settings=settings, planner=planner)  # type: ignore[arg-type]
    )


def first_seen_x(world: World, name: str, until: float) -> float:
    """Where, walking along +x from the origin, `name` first enters the camera's view (truth)."""
    for i in range(int(until * 1000) + 1):
        x = i / 1000
        if any(s.name == name for s in visible_objects(world, Pose2D(x, 0.0, 0.0))):
            return x
    raise AssertionError(f"{name} never comes into view before x={until}")


def test_walk_forward_until_the_red_ball_is_seen_stops_where_it_comes_into_view() -> None:
    world = World(objects=(BALL, PILLAR))
    robot = ScriptedRobot(world)
    result = agent_on(robot).execute_mission("walk forward until you see the red ball")
    entry = first_seen_x(world, "red ball", 5.0)
    end = robot.get_state()
    assert result.success, result.response
    assert abs(end.x - entry) <= 0.2, (end.x, entry)
    assert entry > 0.2  # it had to walk to see it: the pillar hid it at the start
    assert "stopped: saw red ball" in result.response, result.response
    assert "(until you see the red ball)" in result.response
    step = result.steps[0]
    assert step.status is StepStatus.SUCCEEDED and "saw red ball" in step.output


def test_walk_unless_something_is_in_the_way_stops_before_a_person_who_steps_in() -> None:
    robot = ScriptedRobot(World(objects=()), later=PERSON, at_x=1.5)
    result = agent_on(robot).execute_mission("walk forward 5 meters unless something is in the way")
    end = robot.get_state()
    gap = max(
        math.hypot(PERSON.x - t.x, PERSON.y - t.y) - PERSON.radius - robot.config.body_radius
        for t in robot.path[-1:]
    )
    closest = min(
        math.hypot(PERSON.x - t.x, PERSON.y - t.y) - PERSON.radius - robot.config.body_radius
        for t in robot.path
        if t.x >= 1.5
    )
    assert not result.success and result.status is MissionStatus.STOPPED, result.response
    assert closest >= 0.6, (closest, end)
    assert gap >= 0.6
    assert "person in the way" in result.response, result.response
    assert "unless something is in the way" in result.response
    assert end.x > 1.5  # it did walk until the person came


def test_a_walk_until_something_is_seen_goes_no_farther_than_is_clear() -> None:
    """The chair is behind the robot and never comes into view; a box stands 2.5 m ahead. The
    walk "until" is cut short of the box (said in a note) rather than refused, and the body
    never touches the box in truth."""
    box = WorldObject("box", 2.5, 0.0, 0.3, height=0.5)
    robot = ScriptedRobot(World(objects=(box, WorldObject("chair", -4.0, 0.0, 0.3))))
    result = agent_on(robot).execute_mission("walk forward until you see the chair")
    assert result.success, result.response
    assert "short of the box in the way" in result.response, result.response
    clearance = min(
        math.hypot(box.x - t.x, box.y - t.y) - box.radius - robot.config.body_radius
        for t in robot.path
    )
    assert clearance > 0.0, clearance
    assert robot.get_state().x > 1.0  # it did walk as far as was clear
    # The same with a distance the robot may not walk: still cut, never refused or walked.
    again = ScriptedRobot(World(objects=(box,)))
    result = agent_on(again).execute_mission("walk forward 5 meters unless something is in the way")
    assert result.status is MissionStatus.STOPPED and "box in the way" in result.response
    assert again.get_state().x < box.x - box.radius - again.config.body_radius


def test_the_same_walk_with_nobody_in_the_way_goes_the_whole_way() -> None:
    robot = ScriptedRobot(World(objects=()))
    result = agent_on(robot).execute_mission("walk forward 3 meters unless something is in the way")
    assert result.success, result.response
    assert abs(robot.get_state().x - 3.0) < 0.05


def test_stop_if_you_see_a_person_governs_the_walk_before_it() -> None:
    behind = WorldObject("person", -4.0, 3.0, 0.25, height=1.7)  # known to the camera, unseen
    robot = ScriptedRobot(World(objects=(behind,)), later=PERSON, at_x=1.0)
    result = agent_on(robot).execute_mission("walk forward 2 meters and stop if you see a person")
    assert result.status is MissionStatus.STOPPED, result.response
    assert "saw person" in result.response
    assert 1.0 <= robot.get_state().x < 1.2  # stopped at once: the person was in view


def test_a_condition_that_cannot_be_observed_is_refused_naming_it() -> None:
    robot = ScriptedRobot(World(objects=(BALL,)))
    result = agent_on(robot).execute_mission("walk forward 2 meters unless the door is locked")
    assert not result.success
    assert "conditions ('unless') such as 'the door is locked'" in result.response, result.response
    assert robot.get_state().x == 0.0


def test_a_thing_the_camera_cannot_recognise_is_refused_before_moving() -> None:
    robot = ScriptedRobot(World(objects=(BALL,)))
    result = agent_on(robot).execute_mission("walk forward until you see the unicorn")
    assert not result.success
    assert "cannot watch 'until unicorn is seen'" not in result.response  # says the words
    assert "cannot watch 'until you see the unicorn': the camera recognises red ball" in (
        result.response
    ), result.response
    assert robot.get_state().x == 0.0


def test_a_robot_that_cannot_tell_what_is_in_view_refuses_a_watch_by_sight() -> None:
    robot = Minimal()
    plan = Plan(
        [SkillCall("sys.wait", {"seconds": 1.0}, watches=(Watch("until", "seen", "ball"),))]
    )
    result = agent_on(robot, FixedPlanner(plan)).execute_mission("wait until you see a ball")
    assert not result.success
    assert "a minimal robot cannot tell what is in view" in result.response, result.response


def test_a_robot_without_a_scan_or_a_battery_refuses_those_watches() -> None:
    robot = Minimal()
    robot.state = RobotState(battery=None)
    way = Watch("unless", "in_the_way", within=1.0, words="unless something is in the way")
    low = Watch("until", "battery_below", percent=30, words="until the battery is below 30")
    plan = Plan([SkillCall("sys.wait", {"seconds": 1.0}, watches=(way, low))])
    result = agent_on(robot, FixedPlanner(plan)).execute_mission("wait")
    assert "has no range sensor" in result.response, result.response
    assert "reports no battery level" in result.response


def test_until_the_battery_is_low_ends_a_wait_when_it_is() -> None:
    robot = SimRobot(time_scale=0)
    robot.set_battery(31.0)
    agent = agent_on(robot)
    plan = RulePlanner().plan("wait 5 seconds until the battery is below 90 percent")
    assert plan.steps[0].watches[0].percent == 90.0
    robot.set_battery(89.0)
    result = agent.execute_mission("wait 5 seconds until the battery is below 90 percent")
    assert result.success and "the battery is at 89%, below 90%" in result.response
    assert result.steps[0].robot_duration < 1.0  # it held at once, not after 5 s


def test_the_dry_run_shows_the_watches() -> None:
    robot = ScriptedRobot(World(objects=(BALL,)))
    result = agent_on(robot).dry_run("walk forward until you see the red ball")
    assert result.success, result.response
    assert result.plan is not None
    assert result.plan.to_dict()["steps"][0]["watches"] == [
        {"when": "until", "kind": "seen", "name": "red ball", "words": "until you see the red ball"}
    ]


# -- the property: a watch only ever shortens what the governor checked ------------------------


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    distance=st.floats(0.5, 4.5),
    ball_x=st.floats(0.5, 5.5),
    ball_y=st.floats(-3.0, 3.0),
    person_at=st.one_of(st.none(), st.floats(0.0, 4.0)),
    when=st.sampled_from(["until", "unless"]),
    within=st.floats(0.3, 2.0),
)
def test_random_watches_never_take_the_robot_beyond_the_checked_walk(
    distance: float,
    ball_x: float,
    ball_y: float,
    person_at: float | None,
    when: str,
    within: float,
) -> None:
    """Any walk with any watches (seen, in the way) ends no farther than the walk the governor
    checked, and a watch by sight that fires has the robot stopped within a control tick of
    the moment it held in truth (plus braking)."""
    ball = WorldObject("red ball", ball_x, ball_y, 0.15, height=0.3)
    if math.hypot(ball_x, ball_y) < 0.8 or abs(ball_y) < 0.6:
        ball = WorldObject("red ball", ball_x, math.copysign(max(abs(ball_y), 0.6), ball_y), 0.15)
    person = WorldObject("person", (person_at or 0.0) + 1.6, 0.0, 0.25, height=1.7)
    robot = ScriptedRobot(
        World(objects=(ball,)), later=person if person_at is not None else None, at_x=person_at or 0
    )
    watches = (
        Watch(when, "seen", "red ball"),
        Watch(when, "in_the_way", within=within),
    )
    plan = Plan([SkillCall("nav.move", {"distance": round(distance, 2)}, watches=watches)])
    agent = agent_on(robot, FixedPlanner(plan))
    result = agent.execute_mission("walk with watches")
    period = 1.0 / agent.settings.motion.control_rate_hz
    speed = agent.settings.motion.default_linear_speed
    farthest = max((t.x for t in robot.path), default=0.0)
    assert farthest <= round(distance, 2) + 0.05, (farthest, result.response)
    if "saw red ball" in result.response:
        entry = first_seen_x(robot.world, "red ball", farthest + 0.01)
        braking = speed * speed / (2 * agent.settings.safety.max_linear_accel)
        assert robot.get_state().x <= entry + speed * period + braking + 0.02, result.response


_COORD = st.one_of(st.floats(-4.0, 4.0), st.sampled_from([math.nan, math.inf, -math.inf]))


@settings(max_examples=200, deadline=None)
@given(
    x=_COORD,
    y=st.floats(-3.0, 3.0),
    yaw=_COORD,
    distance=st.floats(-6.0, 6.0).filter(lambda d: abs(d) > 0.01),
    when=st.sampled_from(["until", "unless", None]),
    kind=st.sampled_from(["seen", "in_the_way"]),
)
def test_a_fitted_reach_only_ever_shortens_and_never_into_what_is_in_the_way(
    x: float, y: float, yaw: float, distance: float, when: str | None, kind: str
) -> None:
    """From any start (an unknown one too), any straight walk with any watch: checking never
    fails with anything but a refusal; a fitted walk is shorter than asked, in the same
    direction, and the governor finds nothing in its way."""
    from shadowhound.checking import check_plan
    from shadowhound.safety import Governor
    from shadowhound.skills import PlanEnv, default_registry

    robot = SimRobot(time_scale=0)  # the default room: the red ball 3 m ahead, a wall about
    settings = ShadowHoundConfig()
    watches = (Watch(when, kind, "chair", within=1.0),) if when else ()
    plan = Plan([SkillCall("nav.move", {"distance": distance}, watches=watches)])
    start = RobotState(x=x, y=y, yaw=yaw)
    env = PlanEnv(settings, belief=robot.belief(), vocabulary=robot.vocabulary())
    governor = Governor(settings.safety)
    checked = check_plan(plan, default_registry(), governor, settings, env, start, robot=robot)
    for call in checked.calls:
        fitted = call.args.distance  # type: ignore[attr-defined]
        assert abs(fitted) <= abs(distance) + 1e-9 and fitted * distance > 0
        if abs(fitted) < abs(distance) - 1e-9:  # cut: only a walk with such a watch is
            assert when == "until" or kind == "in_the_way"
            assert not any("in the way" in p for p in checked.problems), checked.problems


def test_ten_watches_read_the_robot_once_a_tick() -> None:
    """The watcher reads the view and the scan once for all its watches (bench_watches.py
    measures the cost)."""
    reads = {"view": 0, "scan": 0}

    class Counting(SimRobot):
        def in_view(self) -> tuple[Sighting, ...]:
            reads["view"] += 1
            return super().in_view()

        def get_scan(self) -> Scan | None:
            reads["scan"] += 1
            return super().get_scan()

    robot = Counting(time_scale=0, world=World(objects=(BALL,)))
    watches = [Watch("until", "seen", f"thing {i}") for i in range(8)] + [
        Watch("unless", "in_the_way", within=1.0),
        Watch("until", "battery_below", percent=5),
    ]
    watcher = Watcher(watches, robot, 0.35)
    assert watcher.fired(robot.get_state(), 0.0) is None
    assert reads == {"view": 1, "scan": 1}


def test_a_watch_on_a_reading_names_what_it_saw() -> None:
    robot = SimRobot(time_scale=0, world=World(objects=(BALL,)))
    watcher = Watcher([Watch("until", "seen", "ball", within=3.0)], robot, 0.35)
    far = _Reading(RobotState(), (Sighting("red ball", 4.0, 10.0),), None)
    near = _Reading(RobotState(), (Sighting("red ball", 2.5, -20.0),), None)
    assert watcher.evaluate(far, 0.0) is None  # beyond its "within"
    hit = watcher.evaluate(near, 0.0)
    assert hit is not None and hit[1] == "saw red ball about 2.5 m 20 degrees to the right"


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ("walk forward until you spot a chair", "seen"),
        ("go forward till the red ball is in view", "seen"),
        ("walk ahead 3 m unless someone is in your path", "in_the_way"),
        ("walk forward 2 meters unless the path is blocked", "in_the_way"),
        ("move forward 4 meters but stop if you see a dog", "seen"),
        ("walk backward until the battery drops below 40 percent", "battery_below"),
        ("turn right until you see the door", "seen"),
        ("walk 3 meters unless there's something in front of you", "in_the_way"),
        ("walk 2 meters unless there is an obstacle right ahead", "in_the_way"),
        ("walk forward untill you see the chair", "seen"),  # typos of condition words
        ("walk back 2 meters unles somebody is in the way", "in_the_way"),
    ],
)
def test_the_offline_planner_reads_kinds_of_conditions(text: str, kind: str) -> None:
    plan = RulePlanner().plan(text)
    watched = [w for s in plan.steps for w in s.watches]
    assert watched and watched[0].kind == kind, plan.to_dict()


# -- branches and loops ------------------------------------------------------------------------


def test_when_opens_a_branch_only_before_a_condition_it_can_watch() -> None:
    plan = RulePlanner().plan(
        "when the battery drops under 20 percent head to the charging dock, else patrol twice"
    )
    guards = [(s.skill, s.guard.when if s.guard else None) for s in plan.steps]
    assert guards == [("nav.goto", "if"), ("nav.patrol", "if_not")]
    # "when you get there" says what comes next, not a condition: not a branch.
    with pytest.raises(PlanningError):
        RulePlanner().plan("when you get to the pantry, say hello")


BRANCH = "if the battery is below 30% go to the charging dock, otherwise patrol"


@pytest.mark.parametrize("level", [25.0, 80.0])
def test_if_the_battery_is_low_go_to_the_dock_otherwise_patrol(level: float) -> None:
    """Each branch is taken for its battery level, judged by where the body went in truth."""
    robot = ScriptedRobot(World(objects=(WorldObject("charging dock", -3.0, -1.0, 0.4),)))
    robot.set_battery(level)
    agent = agent_on(robot)
    result = agent.execute_mission(BRANCH)
    assert result.success, result.response
    dock, patrol = result.steps
    end = robot.get_state()
    route = agent.settings.patrol_route
    if level < 30:
        assert (dock.status, patrol.status) == (StepStatus.SUCCEEDED, StepStatus.SKIPPED)
        assert math.hypot(end.x + 3.0, end.y + 1.0) < 1.2, end
        assert "the battery is at 25%, below 30%" in dock.output
        assert patrol.output.startswith("skipped: the battery is at 25%, below 30% (otherwise)")
        assert all(math.dist((t.x, t.y), route[0]) > 0.3 for t in robot.path)  # no patrol
    else:
        assert (dock.status, patrol.status) == (StepStatus.SKIPPED, StepStatus.SUCCEEDED)
        assert dock.output.startswith("skipped: the battery is at 80.0%, not below 30%")
        for point in route:  # the body passed every waypoint of the patrol
            assert min(math.dist((t.x, t.y), point) for t in robot.path) < 0.1, point
        assert math.hypot(end.x, end.y) < 0.1  # and came back
        assert min(math.hypot(t.x + 3.0, t.y + 1.0) for t in robot.path) > 2.0  # never docked


def test_the_dry_run_shows_both_branches() -> None:
    robot = ScriptedRobot(World(objects=(WorldObject("charging dock", -3.0, -1.0, 0.4),)))
    result = agent_on(robot).dry_run(BRANCH)
    assert result.success, result.response
    assert [s.watching() for s in result.steps] == ["if the battery is below 30%", "otherwise"]


def test_patrol_until_i_say_stop_ends_as_asked_when_a_person_stops_it() -> None:
    import threading

    robot = SimRobot(time_scale=1.0)
    agent = agent_on(robot)
    moving = threading.Event()
    agent.add_listener(lambda e: moving.set() if e.kind == "step_started" else None)
    out: dict[str, object] = {}
    runner = threading.Thread(
        target=lambda: out.update(result=agent.execute_mission("patrol until I say stop"))
    )
    runner.start()
    assert moving.wait(20)
    while robot.get_state().distance_travelled < 0.3:  # the body walks (truth), then the stop
        robot.sleep(0.02)
    agent.cancel()
    runner.join(20)
    robot.sleep(0.5)  # braking (the simulator's deceleration) is over by then
    assert robot.get_state().vx == 0.0 and robot.get_state().vy == 0.0
    result = out["result"]
    assert result.success, result.response  # type: ignore[attr-defined]
    assert "stopped: you said stop (until I say stop)" in result.response  # type: ignore[attr-defined]
    assert result.status is MissionStatus.SUCCEEDED  # type: ignore[attr-defined]


def test_after_a_person_says_stop_nothing_more_moves() -> None:
    import threading

    robot = SimRobot(time_scale=1.0)
    agent = agent_on(robot)
    started = threading.Event()
    agent.add_listener(lambda e: started.set() if e.kind == "step_started" else None)
    out: dict[str, object] = {}
    mission = "patrol until I say stop, then walk forward 1 meter"
    runner = threading.Thread(target=lambda: out.update(result=agent.execute_mission(mission)))
    runner.start()
    assert started.wait(20)
    while robot.get_state().distance_travelled < 0.2:
        robot.sleep(0.02)
    agent.cancel()
    runner.join(20)
    result = out["result"]
    assert result.status is MissionStatus.STOPPED  # type: ignore[attr-defined]
    assert result.steps[1].status is StepStatus.SKIPPED  # type: ignore[attr-defined]
    robot.sleep(0.5)  # braking
    at = robot.get_state().distance_travelled
    robot.sleep(1.0)  # the walk after it never starts
    assert robot.get_state().distance_travelled - at < 0.001


@pytest.mark.parametrize(
    ("text", "laps", "watch"),
    [
        ("keep patrolling", None, None),
        ("patrol continuously", None, None),
        ("patrol until I say stop", None, "operator_stop"),
        ("patrol 3 laps until I say stop", 3, "operator_stop"),
        ("while the battery is above 50% patrol", None, "battery_below"),
        ("patrol as long as the battery stays above 40 percent", None, "battery_below"),
    ],
)
def test_the_offline_planner_reads_loops(text: str, laps: int | None, watch: str | None) -> None:
    step = RulePlanner().plan(text).steps[-1]
    assert step.skill == "nav.patrol" and step.args["laps"] == laps
    assert [w.kind for w in step.watches] == ([watch] if watch else [])


def test_keep_patrolling_is_bounded_by_the_missions_limits() -> None:
    """As many laps as the mission's distance allows, checked before it moves."""
    settings = ShadowHoundConfig(safety={"max_mission_distance": 15.0})
    settings.memory.enabled = False
    robot = SimRobot(time_scale=0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    dry = agent.dry_run("keep patrolling")
    assert "at most 2 laps" in dry.response, dry.response  # 6.4 m a lap
    result = agent.execute_mission("keep patrolling")
    assert result.success, result.response
    assert "patrolled 2 laps" in result.response
    assert 12.0 < robot.get_state().distance_travelled <= 15.0  # the truth's odometer


# -- random plans with branches and watches ------------------------------------------------------


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    legs=st.lists(
        st.tuples(
            st.floats(0.2, 1.5),  # metres forward
            st.one_of(st.none(), st.sampled_from(["if", "if_not"])),  # its guard, if any
            st.floats(5.0, 95.0),  # the guard's percent
            st.booleans(),  # watch for the ball too
        ),
        min_size=1,
        max_size=3,
    ),
    battery=st.floats(1.0, 100.0),
    ball_x=st.floats(0.5, 5.0),
)
def test_random_branches_and_watches_never_go_beyond_the_checked_plan(
    legs: list[tuple[float, str | None, float, bool]], battery: float, ball_x: float
) -> None:
    robot = ScriptedRobot(World(objects=(WorldObject("red ball", ball_x, 1.2, 0.15),)))
    robot.set_battery(battery)
    steps = []
    for metres, guard, percent, watch in legs:
        steps.append(
            SkillCall(
                "nav.move",
                {"distance": round(metres, 2)},
                guard=Watch(guard, "battery_below", percent=percent) if guard else None,
                watches=(Watch("until", "seen", "red ball"),) if watch else (),
            )
        )
    result = agent_on(robot, FixedPlanner(Plan(steps))).execute_mission("random plan")
    checked = sum(round(m, 2) for m, *_ in legs)  # every branch, as if no watch fired
    farthest = max((t.x for t in robot.path), default=0.0)
    assert farthest <= checked + 0.05, (farthest, result.response)
    ran = [s for s in result.steps if s.status is not StepStatus.SKIPPED]
    if result.refusals:  # refused whole (a battery below the floor, say): nothing moved
        assert farthest < 0.01 and not ran, result.response
        return
    for step, (_, guard, percent, _) in zip(result.steps, legs, strict=True):
        if guard is not None:  # taken exactly when the guard says (the battery barely drains)
            low = battery < percent
            assert (step.status is not StepStatus.SKIPPED) == (low == (guard == "if")), step
    assert len(ran) <= len(legs)
