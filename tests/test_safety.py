import pytest

from shadowhound import SkillCall, default_registry
from shadowhound.config import SafetyConfig, ShadowHoundConfig
from shadowhound.safety import Governor
from shadowhound.skills import PlanEnv
from shadowhound.state import Pose2D


def check(calls, **limits):
    registry = default_registry()
    settings = ShadowHoundConfig(safety=SafetyConfig(**limits))
    validated = [registry.validate(c) for c in calls]
    return Governor(settings.safety).check_plan(validated, Pose2D(), PlanEnv(settings))


def test_plan_within_limits_passes_and_predicts_path():
    refusals, path = check([SkillCall("nav.move", {"distance": 2}),
                            SkillCall("nav.rotate", {"degrees": 90}),
                            SkillCall("nav.move", {"distance": 1})])
    assert refusals == []
    assert (path[-1].x, path[-1].y) == (pytest.approx(2.0), pytest.approx(1.0))


def test_step_distance_limit():
    refusals, _ = check([SkillCall("nav.move", {"distance": 6})])
    assert "exceeds the limit of 5 m per step" in str(refusals[0])


def test_geofence_counts_the_whole_plan():
    moves = [SkillCall("nav.move", {"distance": 4}) for _ in range(3)]
    refusals, _ = check(moves)
    assert [r.step for r in refusals] == [3]
    assert "outside the geofence of 10 m" in refusals[0].reason


def test_speed_caps():
    refusals, _ = check([SkillCall("nav.move", {"distance": 1, "speed": 0.9}),
                         SkillCall("nav.rotate", {"degrees": 90, "speed": 1.5})])
    assert "0.9 m/s exceeds the cap of 0.5 m/s" in refusals[0].reason
    assert "1.5 rad/s exceeds the cap of 1 rad/s" in refusals[1].reason


def test_risky_tricks_need_approval():
    refusals, _ = check([SkillCall("body.sport", {"trick": "backflip"})])
    assert "risky trick" in refusals[0].reason and "allow_risky_tricks" in refusals[0].reason
    assert check([SkillCall("body.sport", {"trick": "backflip"})],
                 allow_risky_tricks=True)[0] == []
    assert check([SkillCall("body.sport", {"trick": "hello"})])[0] == []


def test_patrol_legs_and_places_are_checked():
    assert check([SkillCall("nav.patrol", {"laps": 2})])[0] == []
    refusals, _ = check([SkillCall("nav.goto", {"place": "attic"})])
    assert "unknown place 'attic'" in refusals[0].reason
    refusals, _ = check([SkillCall("nav.goto", {"x": 30, "y": 0})], max_step_distance=100)
    assert "geofence" in refusals[0].reason
