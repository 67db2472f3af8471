"""Every COCO class name (what a COCO detector reports, and docs/go2.md names: "sports ball",
"potted plant", "dining table", "hot dog", "dog") is a thing a person may ask for in those
words: the offline planner reads it whole, and a robot whose detector knows the class looks for
it, watches for it and goes to it, whether the planner's word for it is the same ("teddy
bear") or another ("sports ball" is the planner's "ball")."""

from __future__ import annotations

import math

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.plan import Watch
from shadowhound.planning.rules import RulePlanner
from shadowhound.robot.go2.detections import _COCO, COCO_CLASSES
from shadowhound.skills import PlanEnv
from shadowhound.skills.objects import resolve
from shadowhound.skills.watches import check_watches
from shadowhound.world import object_key

NAMES = _COCO.split(", ")  # the detector's own class names, as docs/go2.md gives them
PLANNER = RulePlanner()


def test_every_coco_name_is_planned_whole() -> None:
    """ "go to the hot dog" goes to the hot dog (not a place called "hot"), "go to the dog" to
    the dog (not one metre forward: "dog" is what people call the robot only at the end of a
    request with no article before it)."""
    wrong = []
    for name in NAMES:
        for text in (f"go to the {name}", f"find the {name}"):
            steps = [(s.skill, s.args) for s in PLANNER.plan(text).steps]
            if steps != [("nav.goto", {"place": name})]:
                wrong.append((text, steps))
        (walk,) = PLANNER.plan(f"walk forward until you see the {name}").steps
        if [w.name for w in walk.watches] != [name]:
            wrong.append((name, walk.watches))
        text = f"if you see the {name}, sit down"
        guards = [(s.skill, s.guard.name if s.guard else None) for s in PLANNER.plan(text).steps]
        if guards != [("body.sit", name)]:
            wrong.append((text, guards))
    assert not wrong, wrong


def test_a_robot_with_a_coco_detector_looks_for_and_watches_every_coco_name() -> None:
    """Its vocabulary is the planner's words for COCO's classes (`COCO_CLASSES`): the COCO name
    itself is the same thing, to search for and to watch for; a class is never read as a
    misspelling of another ("car" is not "cat")."""
    config = ShadowHoundConfig()
    robot = SimRobot(config.sim, time_scale=0.0)  # a camera that labels what is in view
    vocabulary = frozenset(COCO_CLASSES)
    env = PlanEnv(config, belief=robot.belief(), vocabulary=vocabulary)
    for name in NAMES:
        target = resolve(env, name)
        assert target.search and target.name == name, target  # to look for, as named
        assert check_watches([Watch("until", "seen", name)], robot, vocabulary) == [], name


def test_a_coco_name_and_the_planners_word_name_one_thing() -> None:
    assert object_key("the sports ball") == object_key("ball") == "ball"
    assert object_key("a small potted plant") == "a small plant"
    assert object_key("TV") == "television" and object_key("teddy bear") == "teddy bear"


def test_go_to_the_sports_ball_walks_to_the_ball_in_truth() -> None:
    """On the simulator (whose camera calls it "red ball"), "the sports ball" is the ball: it
    walks there and stands off from it, judged by the simulator's truth."""
    config = ShadowHoundConfig()
    robot = SimRobot(config.sim, time_scale=0.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config))
    agent.initialize()
    ball = next(o for o in robot.world.objects if o.name == "red ball")
    result = agent.execute_mission("go to the sports ball")
    agent.cleanup()
    assert result.success, result.response
    end = robot.get_state()
    gap = math.dist((end.x, end.y), (ball.x, ball.y)) - ball.radius
    assert abs(gap - config.search.standoff) < 0.15, (gap, result.response)
