"""Sightings without ROS: detections -> known objects (frames, refusals), merging by name, and
the RViz conversions (path poses, object markers)."""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace as NS

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.robot.go2.detections import (
    DEFAULT_RADIUS,
    BoxIntake,
    CameraMount,
    DetectionError,
    Frames,
    Reading,
    SightingBoard,
    sightings_from_msg,
    to_sighting,
)
from shadowhound.ros.rviz import LABELS_NS, OBJECTS_NS, object_markers, path_poses
from shadowhound.skills.context import robot_objects
from shadowhound.state import Pose2D
from shadowhound.world import Belief, KnownObject, OccupancyGrid, merge_sightings, object_key

FRAMES = Frames("odom", "base_link")


def test_odom_positions_are_kept_and_body_positions_placed_with_the_robot_pose() -> None:
    pose = Pose2D(1.0, 2.0, math.pi / 2)
    odom = to_sighting("red ball", 3.0, -1.0, "odom", 0.9, 0.2, 5.0, pose, FRAMES)
    assert (odom.name, odom.x, odom.y, odom.radius, odom.confidence, odom.stamp) == (
        "red ball",
        3.0,
        -1.0,
        0.2,
        0.9,
        5.0,
    )
    ahead = to_sighting("  person ", 2.0, 0.0, "/base_link", 0.5, 0.0, 5.0, pose, FRAMES)
    assert ahead.name == "person" and ahead.radius == DEFAULT_RADIUS
    assert math.isclose(ahead.x, 1.0, abs_tol=1e-9) and math.isclose(ahead.y, 4.0)


@pytest.mark.parametrize(
    ("label", "x", "frame", "confidence", "radius", "said"),
    [
        ("", 1.0, "odom", 0.5, 0.0, "needs a label"),
        ("x" * 101, 1.0, "odom", 0.5, 0.0, "at most 100"),
        ("ball", math.nan, "odom", 0.5, 0.0, "finite"),
        ("ball", 1.0, "odom", 1.5, 0.0, "between 0 and 1"),
        ("ball", 1.0, "odom", 0.5, -1.0, "radius"),
        ("ball", 1.0, "camera_link", 0.5, 0.0, "'odom' (the odometry frame) or 'base_link'"),
        ("ball", 1.0, "", 0.5, 0.0, "(empty)"),
    ],
)
def test_bad_detections_are_refused_saying_what_is_allowed(
    label: str, x: float, frame: str, confidence: float, radius: float, said: str
) -> None:
    with pytest.raises(DetectionError) as info:
        to_sighting(label, x, 0.0, frame, confidence, radius, 0.0, Pose2D(), FRAMES)
    assert said in str(info.value)


def detection(label: str, x: float, frame: str = "", sec: int = 0) -> NS:
    return NS(
        label=label,
        position=NS(x=x, y=0.0, z=1.0),
        confidence=0.8,
        radius=0.3,
        header=NS(frame_id=frame, stamp=NS(sec=sec, nanosec=0)),
    )


def test_an_array_uses_its_header_for_detections_that_leave_theirs_empty() -> None:
    msg = NS(
        header=NS(frame_id="odom", stamp=NS(sec=100, nanosec=0)),
        detections=[
            detection("box", 1.0),
            detection("dock", 1.0, "base_link", sec=98),
            detection("cup", 1.0, "camera"),
        ],
    )
    reading = sightings_from_msg(msg, Pose2D(5.0, 0.0, 0.0), FRAMES, 50.0, 100.5)
    assert [(o.name, o.x, o.stamp) for o in reading.seen] == [
        ("box", 1.0, 49.5),
        ("dock", 6.0, 47.5),
    ]
    assert len(reading.problems) == 1 and "'camera' is not supported" in reading.problems[0]
    assert reading.notes == []


names = st.sampled_from(["red ball", "The red ball", "RED  ball", "box", "dock"])
sightings = st.builds(
    KnownObject,
    names,
    st.floats(-5, 5),
    st.floats(-5, 5),
    st.just(0.25),
    st.floats(0, 1),
    st.floats(0, 100),
)


@settings(max_examples=60, deadline=None)
@given(st.lists(sightings, max_size=6), st.lists(sightings, max_size=6))
def test_merging_keeps_one_object_per_name_the_latest_seen(
    known: list[KnownObject], seen: list[KnownObject]
) -> None:
    merged = merge_sightings(merge_sightings((), known), seen)
    keys = [object_key(o.name) for o in merged]
    assert len(keys) == len(set(keys))
    for key in keys:
        got = next(o for o in merged if object_key(o.name) == key)
        same = [o for o in [*known, *seen] if object_key(o.name) == key]
        assert got.stamp == max(o.stamp for o in same)


def test_the_board_forgets_the_longest_unseen_beyond_its_limit() -> None:
    board = SightingBoard(limit=2)
    board.add([KnownObject("a", 0, 0, stamp=1.0), KnownObject("b", 0, 0, stamp=3.0)])
    board.add([KnownObject("c", 0, 0, stamp=2.0)])
    assert [o.name for o in board.objects()] == ["c", "b"]


def test_a_robot_reports_what_it_has_seen_the_latest_sighting_per_name() -> None:
    config = ShadowHoundConfig()
    robot = SimRobot(config.sim, time_scale=0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=config))
    belief = robot.belief()
    assert belief is not None and robot_objects(agent.robot) == ()  # nothing seen yet
    belief.sight("blue box", 2.5, 2.0, stamp=1.0)
    belief.sight("red ball", 3.5, 0.1, stamp=9.0)
    belief.sight("red ball", 3.0, 0.0, stamp=2.0)  # older than the one known: ignored
    objects = {o.name: o for o in robot_objects(agent.robot)}
    assert (objects["red ball"].x, objects["blue box"].x) == (3.5, 2.5)
    assert set(objects) == {"red ball", "blue box"}


def test_path_poses_face_along_each_leg() -> None:
    poses = path_poses([(0, 0), (0, 0), (1, 0), (1, 1)])
    assert [(p.x, p.y) for p in poses] == [(0, 0), (1, 0), (1, 1)]
    assert [round(p.yaw, 6) for p in poses] == [0.0, round(math.pi / 2, 6), round(math.pi / 2, 6)]
    assert path_poses([]) == []


def test_each_object_gets_a_cylinder_its_size_and_a_label() -> None:
    specs = object_markers(
        [KnownObject("red ball", 3.0, 0.0, 0.2, 0.5), KnownObject("box", -1.0, 2.0, 0.35)]
    )
    cylinders = [s for s in specs if s.ns == OBJECTS_NS]
    labels = [s for s in specs if s.ns == LABELS_NS]
    assert [(s.id, s.x, s.y, s.scale[0]) for s in cylinders] == [
        (0, 3.0, 0.0, 0.4),
        (1, -1.0, 2.0, 0.7),
    ]
    assert [s.text for s in labels] == ["red ball", "box"]
    assert cylinders[0].rgba[3] < cylinders[1].rgba[3]  # less sure: fainter


def test_a_new_map_replaces_the_grid_and_keeps_the_objects_known() -> None:
    first = OccupancyGrid.empty(-1.0, 1.0, -1.0, 1.0, value=0)
    belief = Belief(first)
    belief.sight("cup", 0.5, 0.5, stamp=1.0)
    second = OccupancyGrid.empty(-2.0, 2.0, -2.0, 2.0, value=0)
    belief.replace_grid(second)
    assert belief.grid is second and belief.inflated.grid is second
    assert [o.name for o in belief.objects] == ["cup"]


# -- boxes (vision_msgs/Detection2DArray, read by attribute) -------------------------------------


def _stamp(t: float) -> NS:
    return NS(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))


def _box_msg(t: float, *boxes: tuple[str, float, float, float]) -> NS:
    """A Detection2DArray stamped `t` with (class, centre column, width, score) boxes; per
    detection headers left empty, as coco_detector leaves them."""
    return NS(
        header=NS(stamp=_stamp(t), frame_id="camera"),
        detections=[
            NS(
                header=NS(stamp=_stamp(0.0), frame_id=""),
                results=[NS(hypothesis=NS(class_id=c, score=s))] if c else [],
                bbox=NS(center=NS(position=NS(x=u, y=360.0), theta=0.0), size_x=w, size_y=80.0),
                id="",
            )
            for c, u, w, s in boxes
        ],
    )


def test_boxes_become_sightings_with_the_pose_and_scan_at_the_images_stamp() -> None:
    from shadowhound.robot.sim.scene import World, WorldObject
    from shadowhound.robot.sim.sensors import cast_scan
    from shadowhound.world.image_sighting import Bearing, CameraModel

    intake = BoxIntake(CameraMount(0.3, 0.0, 0.0))
    couch = WorldObject("couch", 3.0, 0.0, 0.4)
    world = World(objects=(couch,), bounds=(-10.0, 10.0, -10.0, 10.0))
    assert intake.read(_box_msg(10.0, ("couch", 640.0, 100.0, 0.9)), 10.0).problems == [
        "no camera_info yet: the boxes cannot be turned into bearings"
    ]
    assert intake.on_camera_info([370.0, 0.0, 640.0, 0.0, 370.0, 360.0, 0.0, 0.0, 1.0]) is None
    assert intake.on_camera_info([]) is not None  # kept the good one
    # The robot turned from facing +y to facing +x over one second; the image is at its end.
    for k in range(11):
        intake.on_pose(9.0 + k / 10, Pose2D(0.0, 0.0, math.pi / 2 * (1 - k / 10)), 10.0)
    # Cast where the robot was at 10 s, arriving with a wrong pose: placed by its stamp.
    intake.on_scan(10.0, replace(cast_scan(world, Pose2D()), pose=Pose2D(99.0, 99.0, 0.0)), 10.0)
    camera = CameraModel(370.0, 640.0, 0.3)
    half = math.asin(couch.radius / (couch.x - 0.3))
    left, right = camera.column_of(half), camera.column_of(-half)
    reading = intake.read(
        _box_msg(
            10.0,
            ("couch", (left + right) / 2, right - left, 0.8),
            ("tv", 100.0, 30.0, 0.7),  # to the left: only the wall 10 m off, beyond 6 m
            ("", 600.0, 10.0, 0.5),
        ),
        10.1,
    )
    seen, bearings, problems = reading.seen, reading.bearings, reading.problems
    assert problems == ["a detection without a class (results is empty)"]
    assert [(o.name, o.stamp) for o in seen] == [("sofa", 10.0)]
    assert math.hypot(seen[0].x - couch.x, seen[0].y - couch.y) < 0.1
    assert [b.name for b in bearings] == ["television"] and isinstance(bearings[0], Bearing)
    assert intake.bearings() == tuple(bearings)
    # An image from before the odometry history has no pose: refused, never guessed.
    assert intake.read(_box_msg(5.0, ("chair", 640.0, 50.0, 0.9)), 10.2).problems == [
        "'chair': no odometry pose at the image's time 5.00"
    ]


def _couch_in_view() -> tuple[BoxIntake, NS, object]:
    """An intake with a camera, and the box of a couch 3 m ahead of a robot at the origin
    facing +x, stamped 10 s, with the scan of that moment."""
    from shadowhound.robot.sim.scene import World, WorldObject
    from shadowhound.robot.sim.sensors import cast_scan
    from shadowhound.world.image_sighting import CameraModel

    intake = BoxIntake(CameraMount(0.3, 0.0, 0.0))
    intake.on_camera_info([370.0, 0.0, 640.0, 0.0, 370.0, 360.0, 0.0, 0.0, 1.0])
    couch = WorldObject("couch", 3.0, 0.0, 0.4)
    intake.on_scan(10.0, cast_scan(World(objects=(couch,)), Pose2D()), 10.0)
    half = math.asin(couch.radius / (couch.x - 0.3))
    camera = CameraModel(370.0, 640.0, 0.3)
    left, right = camera.column_of(half), camera.column_of(-half)
    return intake, _box_msg(10.0, ("couch", (left + right) / 2, right - left, 0.8)), couch


def test_a_box_seen_while_turning_waits_for_the_odometry_of_its_time() -> None:
    """Issue 24: odometry comes late (go2_ros2_sdk's, 0.2 s and more). A box seen while the
    robot turned, newer than the last odometry, is not placed from that older pose (seen from
    there the couch would land 0.8 m off): it waits for the pose of its time."""
    intake, box, couch = _couch_in_view()
    for k in range(9):  # turning right at 1.5 rad/s, odometry so far up to 9.8 s
        intake.on_pose(9.0 + k / 10, Pose2D(0.0, 0.0, 0.15 * (10 - k - 1) + 0.15), 10.0)
    assert intake.read(box, 10.1) == Reading()  # held
    intake.on_pose(9.9, Pose2D(0.0, 0.0, 0.15), 10.0)
    intake.on_pose(10.0, Pose2D(), 10.0)
    reading = intake.read(_box_msg(10.5), 10.6)  # the next array: nothing in view
    assert reading.problems == [] and reading.bearings == []
    seen = reading.seen
    assert [o.name for o in seen] == ["sofa"] and seen[0].stamp == 10.0
    assert math.hypot(seen[0].x - couch.x, seen[0].y - couch.y) < 0.05
    assert intake.read(_box_msg(11.0), 11.1) == Reading()  # placed once


def test_a_box_seen_at_rest_is_placed_at_once_and_one_whose_odometry_never_comes_is_refused():
    intake, box, couch = _couch_in_view()
    for k in range(9):  # standing still: odometry up to 9.8 s, late, but the robot is there
        intake.on_pose(9.0 + k / 10, Pose2D(), 10.0)
    reading = intake.read(box, 10.1)
    seen, problems = reading.seen, reading.problems
    assert problems == [] and [o.name for o in seen] == ["sofa"]
    assert math.hypot(seen[0].x - couch.x, seen[0].y - couch.y) < 0.05
    turning, box, _couch = _couch_in_view()
    for k in range(9):
        turning.on_pose(9.0 + k / 10, Pose2D(0.0, 0.0, 0.1 * k), 10.0)
    assert turning.read(box, 10.1) == Reading()  # held...
    assert turning.read(_box_msg(11.9), 12.0) == Reading()  # ... up to 2 s
    assert turning.read(_box_msg(12.1), 12.2).problems == [
        "'couch': no odometry pose at the image's time 10.00"
    ]
