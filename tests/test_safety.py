import pytest

from shadowhound import SkillCall, default_registry
from shadowhound.config import SafetyConfig, ShadowHoundConfig
from shadowhound.safety import Governor, inside_polygon
from shadowhound.skills import PlanEnv
from shadowhound.state import Posture, RobotState


def check(calls, start=None, auto_stand=True, **limits):
    registry = default_registry()
    settings = ShadowHoundConfig(safety=SafetyConfig(**limits))
    validated = [registry.validate(c) for c in calls]
    start = start or RobotState()
    return Governor(settings.safety, auto_stand).check_plan(
        validated, start, PlanEnv(settings, start.pose)
    )


def reasons(verdict):
    return [str(r) for r in verdict.refusals]


def test_plan_within_limits_passes_and_predicts_path():
    verdict = check(
        [
            SkillCall("nav.move", {"distance": 2}),
            SkillCall("nav.rotate", {"degrees": 90}),
            SkillCall("nav.move", {"distance": 1}),
        ]
    )
    assert verdict.refusals == [] and verdict.approvals == []
    assert (verdict.path[-1].x, verdict.path[-1].y) == (pytest.approx(2.0), pytest.approx(1.0))
    assert verdict.distance == pytest.approx(3.0)


def test_step_distance_limit():
    assert (
        "exceeds the limit of 5 m per step"
        in reasons(check([SkillCall("nav.move", {"distance": 6})]))[0]
    )


def test_geofence_counts_the_whole_plan():
    verdict = check([SkillCall("nav.move", {"distance": 4}) for _ in range(3)])
    assert [r.step for r in verdict.refusals] == [3]
    assert "outside the geofence of 10 m" in verdict.refusals[0].reason


def test_polygon_geofence_including_non_convex_crossings():
    l_shape = [(-1, -1), (4, -1), (4, 1), (1, 1), (1, 4), (-1, 4)]
    assert inside_polygon(0, 0, l_shape) and not inside_polygon(3, 3, l_shape)
    ok = check([SkillCall("nav.goto", {"x": 3, "y": 0})], geofence_polygon=l_shape)
    assert ok.refusals == []
    out = check([SkillCall("nav.goto", {"x": 3, "y": 3})], geofence_polygon=l_shape)
    assert "leaves the geofence polygon" in reasons(out)[0]
    # Both ends inside, but the straight leg cuts across the missing corner.
    legs = [SkillCall("nav.goto", {"x": 3, "y": 0.5}), SkillCall("nav.goto", {"x": 0, "y": 3})]
    cut = check(legs, geofence_polygon=l_shape)
    assert [r.step for r in cut.refusals] == [2]


def test_mission_distance_limit():
    moves = [SkillCall("nav.move", {"distance": d}) for d in (4, -4, 4, -4)]
    verdict = check(moves, max_mission_distance=10)
    assert [r.step for r in verdict.refusals] == [3, 4]
    assert "more than the limit of 10 m" in verdict.refusals[0].reason


def test_speed_caps():
    verdict = check(
        [
            SkillCall("nav.move", {"distance": 1, "speed": 0.9}),
            SkillCall("nav.rotate", {"degrees": 90, "speed": 1.5}),
        ]
    )
    assert "0.9 m/s exceeds the cap of 0.5 m/s" in verdict.refusals[0].reason
    assert "1.5 rad/s exceeds the cap of 1 rad/s" in verdict.refusals[1].reason


def test_risky_tricks_need_approval_unless_allowed():
    verdict = check([SkillCall("body.sport", {"trick": "backflip"})])
    assert verdict.refusals == [] and "needs approval" in verdict.approvals[0].reason
    assert (
        check([SkillCall("body.sport", {"trick": "backflip"})], allow_risky_tricks=True).approvals
        == []
    )
    assert check([SkillCall("body.sport", {"trick": "hello"})]).approvals == []


def test_battery_floor_allows_only_stopping_and_sitting():
    low = RobotState(battery=9.0)
    verdict = check(
        [
            SkillCall("nav.move", {"distance": 1}),
            SkillCall("body.sit"),
            SkillCall("nav.stop"),
            SkillCall("sys.status"),
        ],
        start=low,
    )
    assert [r.step for r in verdict.refusals] == [1]
    assert "battery is at 9%, below the floor of 15%" in verdict.refusals[0].reason


def test_allow_and_deny_lists():
    verdict = check(
        [SkillCall("nav.move", {"distance": 1}), SkillCall("body.sport", {"trick": "dance1"})],
        allow_skills=["nav.*", "sys.*"],
    )
    assert [r.step for r in verdict.refusals] == [2]
    verdict = check([SkillCall("perception.look_around")], deny_skills=["perception.*"])
    assert "safety.deny_skills" in verdict.refusals[0].reason


def test_posture_preconditions_when_auto_stand_is_off():
    sitting = RobotState(posture=Posture.SITTING)
    verdict = check([SkillCall("nav.move", {"distance": 1})], start=sitting, auto_stand=False)
    assert "will be sitting here; add body.stand" in verdict.refusals[0].reason
    assert (
        check(
            [SkillCall("body.stand"), SkillCall("nav.move", {"distance": 1})],
            start=sitting,
            auto_stand=False,
        ).refusals
        == []
    )
    assert check([SkillCall("nav.move", {"distance": 1})], start=sitting).refusals == []


def test_patrol_legs_and_places_are_checked():
    assert check([SkillCall("nav.patrol", {"laps": 2})]).refusals == []
    attic = reasons(check([SkillCall("nav.goto", {"place": "attic"})]))[0]
    assert "'attic' is not a place or an object I know" in attic
    verdict = check([SkillCall("nav.goto", {"x": 30, "y": 0})], max_step_distance=100)
    assert "geofence" in verdict.refusals[0].reason


def test_an_unknown_battery_is_said_not_pretended_and_a_known_low_one_refuses():
    unknown = check([SkillCall("nav.move", {"distance": 1})], start=RobotState(battery=None))
    assert unknown.refusals == []
    assert unknown.notes == [
        "battery level unknown (the robot reports none): the battery floor "
        "of 15% (safety.battery_floor) cannot be checked"
    ]
    low = check([SkillCall("nav.move", {"distance": 1})], start=RobotState(battery=14.9))
    assert "battery is at 15%, below the floor of 15%" in reasons(low)[0] and low.notes == []
    assert (
        check([SkillCall("nav.move", {"distance": 1})], start=RobotState(battery=15.0)).refusals
        == []
    )
