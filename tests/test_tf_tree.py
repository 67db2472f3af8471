"""The TF tree: lookups through map -> odom -> base_link and static frames, interpolation in the
history, map -> odom corrections, poses carried between map and odom, and stamps from the future
(or too old) refused, so they never hold off the honest samples after them."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shadowhound.errors import TransformUnavailable
from shadowhound.robot.go2.stamps import STAMP_AHEAD
from shadowhound.robot.tf_tree import (
    BASE,
    MAP,
    ODOM,
    TfTree,
    Transform2D,
    interpolate,
)
from shadowhound.state import Pose2D, normalize_angle

coordinate = st.floats(-1.0e3, 1.0e3, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
transforms = st.builds(Transform2D, coordinate, coordinate, angle)
poses = st.builds(Pose2D, coordinate, coordinate, angle)


def close(a: Transform2D | Pose2D, b: Transform2D | Pose2D, tol: float = 1e-9) -> bool:
    return (
        math.isclose(a.x, b.x, abs_tol=tol)
        and math.isclose(a.y, b.y, abs_tol=tol)
        and abs(normalize_angle(a.yaw - b.yaw)) <= tol
    )


def robot_tree() -> TfTree:
    tree = TfTree(keep=5.0)
    tree.set_map_to_odom(10.0, Transform2D(1.0, 2.0, math.pi / 2), now=10.0)
    tree.set_odom_to_base(10.0, Transform2D(3.0, 0.0, 0.0), now=10.0)
    tree.set_static(BASE, "camera", Transform2D(0.3, 0.0, 0.0))
    return tree


def test_lookup_composes_along_the_chain() -> None:
    tree = robot_tree()
    # base_link at (3, 0) in odom; odom turned a quarter and moved to (1, 2) in the map.
    assert close(tree.lookup(MAP, BASE), Transform2D(1.0, 5.0, math.pi / 2))
    assert close(tree.lookup(MAP, "camera"), Transform2D(1.0, 5.3, math.pi / 2))
    assert close(tree.lookup("camera", MAP), tree.lookup(MAP, "camera").inverse())
    assert close(tree.lookup(ODOM, ODOM), Transform2D())


def test_a_pose_goes_between_map_and_odom() -> None:
    tree = robot_tree()
    in_map = tree.to_map(Pose2D(1.0, 0.0, 0.0))
    assert close(in_map, Pose2D(1.0, 3.0, math.pi / 2))
    assert close(tree.to_odom(in_map), Pose2D(1.0, 0.0, 0.0))


def test_lookup_interpolates_between_two_samples() -> None:
    tree = TfTree()
    tree.set_map_to_odom(1.0, Transform2D(0.0, 0.0, math.radians(170)), now=1.0)
    tree.set_map_to_odom(3.0, Transform2D(2.0, -4.0, math.radians(-170)), now=3.0)
    halfway = tree.lookup(MAP, ODOM, 2.0)
    # Yaw goes the short way, through pi, not back through zero.
    assert close(halfway, Transform2D(1.0, -2.0, math.pi))
    assert close(tree.lookup(MAP, ODOM, 3.0), Transform2D(2.0, -4.0, math.radians(-170)))
    assert close(tree.lookup(MAP, ODOM), Transform2D(2.0, -4.0, math.radians(-170)))


def test_samples_out_of_order_and_repeated_are_kept_in_stamp_order() -> None:
    tree = TfTree()
    tree.set_map_to_odom(3.0, Transform2D(3.0, 0.0, 0.0), now=3.0)
    tree.set_map_to_odom(1.0, Transform2D(1.0, 0.0, 0.0), now=3.0)  # late
    tree.set_map_to_odom(3.0, Transform2D(5.0, 0.0, 0.0), now=3.0)  # re-sent: replaces
    assert close(tree.lookup(MAP, ODOM, 2.0), Transform2D(3.0, 0.0, 0.0))


def test_history_is_only_as_long_as_kept_and_outside_it_is_refused() -> None:
    tree = TfTree(keep=2.0)
    for stamp in range(10):
        tree.set_map_to_odom(float(stamp), Transform2D(float(stamp), 0.0, 0.0), now=float(stamp))
    assert close(tree.lookup(MAP, ODOM, 7.5), Transform2D(7.5, 0.0, 0.0))
    with pytest.raises(TransformUnavailable, match="7.000 s to 9.000 s"):
        tree.lookup(MAP, ODOM, 6.5)
    with pytest.raises(TransformUnavailable, match="not known at 9.500 s"):
        tree.lookup(MAP, ODOM, 9.5)


def test_static_transforms_hold_at_any_stamp() -> None:
    tree = TfTree()
    tree.set_static(BASE, "lidar", Transform2D(0.2, 0.0, math.pi))
    assert close(tree.lookup(BASE, "lidar", 1.0e6), Transform2D(0.2, 0.0, math.pi))


def test_unknown_frames_two_trees_loops_and_second_parents_are_refused() -> None:
    tree = robot_tree()
    with pytest.raises(TransformUnavailable, match="no frame 'earth'"):
        tree.lookup(MAP, "earth")
    tree.set_static("world", "marker", Transform2D())
    with pytest.raises(TransformUnavailable, match="two trees"):
        tree.lookup(MAP, "marker")
    with pytest.raises(TransformUnavailable, match="loop"):
        tree.set_static("camera", MAP, Transform2D())
    with pytest.raises(TransformUnavailable, match="already has the parent odom"):
        tree.set_transform("world", BASE, 11.0, Transform2D(), now=11.0)
    with pytest.raises(TransformUnavailable, match="not finite"):
        tree.set_odom_to_base(11.0, Transform2D(math.nan, 0.0, 0.0), now=11.0)
    with pytest.raises(TransformUnavailable, match="stamp"):
        tree.set_odom_to_base(math.inf, Transform2D(), now=11.0)
    assert close(tree.lookup(ODOM, BASE), Transform2D(3.0, 0.0, 0.0))  # nothing bad was kept


def test_a_map_to_odom_correction_beyond_the_thresholds_is_reported() -> None:
    tree = TfTree(jump_distance=0.2, jump_yaw=math.radians(10))
    assert tree.map_to_odom_jump(0.0) is None  # no map yet
    tree.set_map_to_odom(1.0, Transform2D(), now=1.0)
    tree.set_odom_to_base(1.0, Transform2D(10.0, 0.0, 0.0), now=1.0)
    tree.set_map_to_odom(2.0, Transform2D(0.1, 0.0, 0.0), now=2.0)  # SLAM nudges: small
    assert tree.map_to_odom_jump(1.0) is None
    # A small turn of odom about its origin moves a robot 10 m away by far more than 0.2 m.
    tree.set_map_to_odom(3.0, Transform2D(0.1, 0.0, math.radians(5)), now=3.0)
    jump = tree.map_to_odom_jump(2.5)
    assert jump is not None
    assert (jump.since, jump.stamp) == (2.0, 3.0)
    assert jump.distance == pytest.approx(2 * 10.0 * math.sin(math.radians(2.5)))
    assert jump.yaw == pytest.approx(math.radians(5))
    assert tree.map_to_odom_jump(3.0) is None  # nothing since the latest
    assert tree.map_to_odom_jump(-100.0) is not None  # older than kept: from the oldest


def test_a_turn_alone_beyond_the_yaw_threshold_is_reported() -> None:
    tree = TfTree(jump_distance=0.2, jump_yaw=math.radians(10))
    tree.set_map_to_odom(1.0, Transform2D(), now=1.0)
    tree.set_map_to_odom(2.0, Transform2D(0.0, 0.0, math.radians(15)), now=2.0)
    jump = tree.map_to_odom_jump(1.0)
    assert jump is not None and jump.distance == pytest.approx(0.0)


@given(transforms, transforms, poses)
def test_composing_then_inverting_returns_the_pose(
    a: Transform2D, b: Transform2D, p: Pose2D
) -> None:
    chain = a.compose(b)
    back = chain.inverse().apply(chain.apply(p))
    assert close(back, p, 1e-9)
    assert close(b.inverse().apply(a.inverse().apply(chain.apply(p))), p, 1e-9)


@given(transforms, poses)
def test_a_pose_to_the_map_and_back_is_the_pose(map_odom: Transform2D, p: Pose2D) -> None:
    tree = TfTree()
    tree.set_map_to_odom(0.0, map_odom, now=0.0)
    assert close(tree.to_odom(tree.to_map(p)), p, 1e-9)


@given(transforms, transforms, st.floats(0.0, 1.0))
def test_interpolation_lies_between_the_two_samples(
    a: Transform2D, b: Transform2D, fraction: float
) -> None:
    tree = TfTree()
    tree.set_map_to_odom(1.0, a, now=1.0)
    tree.set_map_to_odom(2.0, b, now=2.0)
    mid = tree.lookup(MAP, ODOM, 1.0 + fraction)
    assert close(mid, interpolate(a, b, fraction), 1e-9)
    assert min(a.x, b.x) - 1e-9 <= mid.x <= max(a.x, b.x) + 1e-9
    assert min(a.y, b.y) - 1e-9 <= mid.y <= max(a.y, b.y) + 1e-9
    # yaw on the shorter arc from a to b: no farther from either end than the arc is long
    arc = abs(normalize_angle(b.yaw - a.yaw))
    from_a, from_b = abs(normalize_angle(mid.yaw - a.yaw)), abs(normalize_angle(b.yaw - mid.yaw))
    assert from_a + from_b == pytest.approx(arc, abs=1e-9)


def test_a_stamp_from_the_future_is_refused_and_later_corrections_are_taken() -> None:
    """Issue 32: three map -> odom stamped 1,000 s ahead made every real correction after them
    look old: the newest by stamp stayed the forged one."""
    tree = TfTree()
    tree.set_map_to_odom(100.0, Transform2D(0.0, 0.0, 0.0), now=100.0)
    for arrival in (100.1, 100.2, 100.3):
        with pytest.raises(TransformUnavailable, match="1000.0 s ahead of this computer's clock"):
            tree.set_map_to_odom(arrival + 1000.0, Transform2D(5.0, 5.0, 1.0), now=arrival)
    tree.set_map_to_odom(100.5, Transform2D(0.3, 0.0, 0.0), now=100.5)
    assert close(tree.lookup(MAP, ODOM), Transform2D(0.3, 0.0, 0.0))
    jump = tree.map_to_odom_jump(100.0)
    assert jump is not None and jump.stamp == 100.5
    # Post-dated as AMCL does (transform_tolerance, 1 s): taken.
    tree.set_map_to_odom(101.6, Transform2D(0.4, 0.0, 0.0), now=100.6)
    assert close(tree.lookup(MAP, ODOM), Transform2D(0.4, 0.0, 0.0))
    # Older than the history kept, by this computer's clock: refused, never the latest.
    with pytest.raises(TransformUnavailable, match="before this computer's clock"):
        tree.set_odom_to_base(0.0, Transform2D(), now=100.7)
    assert BASE not in tree.frames()


HONEST = st.floats(-3.0, STAMP_AHEAD)  # seconds from the arrival: late, or post-dated
FORGED = st.one_of(
    st.floats(STAMP_AHEAD + 0.01, 1.0e9),
    st.floats(-1.0e9, -10.01),
    st.sampled_from([math.inf, -math.inf, math.nan]),
)


@st.composite
def tf_streams(draw: st.DrawFn) -> list[tuple[bool, str, float, float, Transform2D]]:
    """(honest, edge, arrival, stamp, transform): arrivals in order, each stamp honest (late or
    post-dated within the window) or forged (far ahead, far behind, not a time)."""
    out = []
    arrival = 1000.0
    for _ in range(draw(st.integers(1, 30))):
        arrival += draw(st.floats(0.0, 2.0))
        honest = draw(st.booleans())
        offset = draw(HONEST if honest else FORGED)
        edge = draw(st.sampled_from([ODOM, BASE]))
        out.append((honest, edge, arrival, arrival + offset, draw(transforms)))
    return out


def feed(tree: TfTree, stream: list[tuple[bool, str, float, float, Transform2D]]) -> None:
    for _honest, edge, arrival, stamp, transform in stream:
        parent = MAP if edge == ODOM else ODOM
        try:
            tree.set_transform(parent, edge, stamp, transform, now=arrival)
        except TransformUnavailable as exc:
            assert "not kept" in str(exc)


def answers(tree: TfTree, stamps: list[float]) -> list[object]:
    out: list[object] = [tree.frames()]
    for target, source in ((MAP, ODOM), (ODOM, BASE), (MAP, BASE)):
        for stamp in [None, *stamps]:
            try:
                out.append(tree.lookup(target, source, stamp))
            except TransformUnavailable as exc:
                out.append(str(exc))
    out.extend(tree.map_to_odom_jump(s) for s in stamps)
    return out


@given(tf_streams(), st.lists(st.floats(990.0, 1070.0), max_size=5))
def test_forged_stamps_change_nothing_the_honest_samples_say(
    stream: list[tuple[bool, str, float, float, Transform2D]], asked: list[float]
) -> None:
    """Whatever forged samples come between them, the tree answers every question (latest,
    at a stamp, the map -> odom jump since a stamp) as the honest samples alone make it."""
    everything, honest = TfTree(), TfTree()
    feed(everything, stream)
    feed(honest, [s for s in stream if s[0]])
    assert answers(everything, asked) == answers(honest, asked)
