"""What a Go2 takes of one detection message, without ROS (issue 32, items 4 and 7): the most
confident boxes up to the cap, saying so; stamps outside the window of the node's clock refused,
so a box from the future never holds off the honest ones after it; the input report."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.robot.go2.detections import BoxIntake, CameraMount, Frames, sightings_from_msg
from shadowhound.robot.go2.stamps import STAMP_AHEAD
from shadowhound.robot.input_limits import MAX_BOXES, InputReport, most_confident, size_words
from shadowhound.robot.sim.scene import World, WorldObject
from shadowhound.robot.sim.sensors import cast_scan
from shadowhound.state import Pose2D
from shadowhound.world.image_sighting import CameraModel
from tests.test_sightings import _box_msg, _stamp

CAMERA = CameraModel(370.0, 640.0, 0.3)
COUCH = WorldObject("couch", 3.0, 0.0, 0.4)


def couch_box() -> tuple[str, float, float, float]:
    half = math.asin(COUCH.radius / (COUCH.x - 0.3))
    left, right = CAMERA.column_of(half), CAMERA.column_of(-half)
    return ("couch", (left + right) / 2, right - left, 0.8)


def intake_at_rest(until: float) -> BoxIntake:
    """An intake with a camera, a robot standing at the origin (odometry up to `until`) and
    the scan of the couch 3 m ahead."""
    intake = BoxIntake(CameraMount(0.3, 0.0, 0.0))
    intake.on_camera_info([370.0, 0.0, 640.0, 0.0, 370.0, 360.0, 0.0, 0.0, 1.0])
    t = max(0.0, until - 5.0)
    while t <= until:
        assert intake.on_pose(t, Pose2D(), until) is None
        t += 0.5
    assert intake.on_scan(until, cast_scan(World(objects=(COUCH,)), Pose2D()), until) is None
    return intake


def test_most_confident_keeps_the_highest_scores_in_their_order() -> None:
    assert most_confident([3, 1, 4, 1, 5, 9, 2, 6], float, 3) == [5, 9, 6]
    assert most_confident([1, 2], float, 3) == [1, 2]


def test_a_thousand_boxes_are_read_as_the_most_confident_hundred_saying_so() -> None:
    intake = intake_at_rest(10.0)
    boxes = [("person", 100.0 + i, 10.0, 0.3 + i / 10_000) for i in range(999)]
    msg = _box_msg(10.0, *boxes, couch_box())  # the couch is the most confident of all
    reading = intake.read(msg, 10.1)
    assert len(reading.seen) + len(reading.bearings) + len(reading.problems) <= MAX_BOXES
    assert [o.name for o in reading.seen] == ["sofa"]
    assert reading.notes == [
        ("too many", f"1000 detections in one message: read the {MAX_BOXES} most confident")
    ]
    kept_columns = sorted(b.direction for b in reading.bearings)
    assert len(kept_columns) == MAX_BOXES - 1  # the 99 most confident people: no range
    # positions the model gave: only the last 99 (the highest scores) of the people
    assert min(CAMERA.column_of(d) for d in kept_columns) > 100.0 + 999 - MAX_BOXES - 1


def test_a_thousand_positions_are_read_as_the_most_confident_hundred() -> None:
    detections = [
        NS(
            label=f"thing {i}",
            position=NS(x=1.0, y=0.0, z=0.0),
            confidence=i / 1000,
            radius=0.2,
            header=NS(frame_id="", stamp=_stamp(0.0)),
        )
        for i in range(1000)
    ]
    msg = NS(header=NS(frame_id="odom", stamp=_stamp(100.0)), detections=detections)
    reading = sightings_from_msg(msg, Pose2D(), Frames(), 50.0, 100.0)
    assert [o.name for o in reading.seen] == [f"thing {i}" for i in range(900, 1000)]
    assert reading.notes[0][1].startswith("1000 detections in one message")


def test_boxes_stamped_from_the_future_or_long_ago_are_refused_saying_why() -> None:
    intake = intake_at_rest(100.0)
    future = intake.read(_box_msg(1100.0, couch_box()), 100.0)
    assert future.seen == [] and future.notes == [
        (
            "stamp",
            "an image's boxes stamped 1000.0 s ahead of this computer's clock (at most 2 s is "
            "taken: a clock set wrong, or a forged message): refused",
        )
    ]
    old = intake.read(_box_msg(50.0, couch_box()), 100.0)
    assert old.seen == [] and "50.0 s before this computer's clock" in old.notes[0][1]
    honest = intake.read(_box_msg(100.0, couch_box()), 100.1)
    assert [o.name for o in honest.seen] == ["sofa"] and honest.notes == []


def test_a_position_stamped_from_the_future_is_refused() -> None:
    future = NS(
        label="red ball",
        position=NS(x=1.0, y=0.0, z=0.0),
        confidence=0.9,
        radius=0.2,
        header=NS(frame_id="odom", stamp=_stamp(1100.0)),
    )
    msg = NS(header=NS(frame_id="odom", stamp=_stamp(100.0)), detections=[future])
    reading = sightings_from_msg(msg, Pose2D(), Frames(), 50.0, 100.0)
    assert reading.seen == [] and "1000.0 s ahead" in reading.notes[0][1]


# Each image: its time after the last (s), and its stamp's offset from that time: honest (late,
# or slightly ahead) or forged (far ahead, far behind).
HONEST = st.floats(-1.0, STAMP_AHEAD)
FORGED = st.one_of(st.floats(STAMP_AHEAD + 0.01, 1e6), st.floats(-1e6, -10.01))
LAG = 0.3  # seconds odometry comes late


def turning(t: float) -> Pose2D:
    return Pose2D(0.0, 0.0, math.remainder(0.2 * t, math.tau))


@settings(max_examples=80, deadline=None)
@given(st.lists(st.tuples(st.floats(0.05, 1.0), st.booleans(), HONEST, FORGED), max_size=12))
def test_forged_stamps_change_nothing_the_honest_boxes_give(
    images: list[tuple[float, bool, float, float]],
) -> None:
    """A robot turns; odometry comes late, so boxes wait for the pose of their time. Whatever
    forged images, poses and scans come between them, the honest boxes give what they alone
    would (a box from the future used to wait forever, and made every honest box after it too
    old to wait; a pose from the future answered for every time before it)."""
    everything, honest = intake_at_rest(0.0), intake_at_rest(0.0)
    scan = cast_scan(World(objects=(COUCH,)), Pose2D())
    arrival, odometry = 100.0, 100.0 - LAG
    for gap, is_honest, late, forged in images:
        arrival += gap
        while odometry < arrival - LAG:  # odometry and scans of the turning robot
            odometry += 0.05
            for intake in (everything, honest):
                assert intake.on_pose(odometry, turning(odometry), arrival) is None
                assert intake.on_scan(odometry, scan, arrival) is None
        if not is_honest:  # a forged pose and scan too, from the same clock
            assert everything.on_pose(arrival + forged, Pose2D(5.0, 5.0, 1.0), arrival)
            assert everything.on_scan(arrival + forged, scan, arrival)
        msg = _box_msg(arrival + (late if is_honest else forged), couch_box())
        got = everything.read(msg, arrival)
        if is_honest:
            assert got == honest.read(msg, arrival)
        else:
            assert got.seen == [] and got.notes[0][0] == "stamp"


def test_the_report_logs_a_kind_when_it_begins_and_keeps_counting() -> None:
    report = InputReport(quiet=30.0, recent=60.0)
    assert report.note("/tf", "map -> odom", "stamped 999.9 s ahead", 0.0) is True
    assert report.note("/tf", "map -> odom", "stamped 998.0 s ahead", 1.0) is False
    assert report.note("/boxes", "too many", "1000 detections", 2.0) is True
    assert report.note("/tf", "map -> odom", "stamped 997.0 s ahead", 31.0) is True
    assert report.summary(32.0) == ("/tf: stamped 997.0 s ahead (3 times); /boxes: 1000 detections")
    assert report.summary(100.0) == ""  # nothing for a minute
    assert (size_words(512), size_words(64 * 1024), size_words(3 * 1024 * 1024)) == (
        "512 bytes",
        "64 KB",
        "3.0 MB",
    )
