"""`shadowhound doctor --go2`, the rest of the stack: TF and SLAM's map, the detector and its
camera model, the voice (pure rules on observations; over DDS: tests/ros/test_go2_doctor_stack.py).
"""

from __future__ import annotations

import itertools

from shadowhound.ros.go2_doctor import Endpoint, Observation, diagnose
from shadowhound.ros.go2_doctor_stack import (
    CAMERA_INFO_TYPE,
    DETECTIONS_TYPE,
    MAP_TYPE,
    SPEECH_TYPE,
    STACK_UPSTREAM_HASHES,
    TF_TYPE,
    stack_findings,
)
from tests.test_go2_doctor import DRIVER, healthy

SLAM = "/slam_toolbox"
COCO = "/coco_detector_node"
TTS = "/tts_node"


def stack(**changes: object) -> Observation:
    """A healthy driver with the whole stack: SLAM, the detector, the voice."""
    obs = healthy()
    obs.names.update(
        tf="/tf",
        tf_static="/tf_static",
        map="/map",
        coco_detections="/detected_objects",
        camera_info="/camera/camera_info",
        speech="/tts",
    )
    obs.publishers.update(
        tf=[
            Endpoint(DRIVER, TF_TYPE, STACK_UPSTREAM_HASHES[TF_TYPE]),
            Endpoint(SLAM, TF_TYPE, STACK_UPSTREAM_HASHES[TF_TYPE]),
        ],
        map=[Endpoint(SLAM, MAP_TYPE)],
        coco_detections=[Endpoint(COCO, DETECTIONS_TYPE, STACK_UPSTREAM_HASHES[DETECTIONS_TYPE])],
        camera_info=[Endpoint(DRIVER, CAMERA_INFO_TYPE)],
    )
    obs.subscribers["speech"] = [Endpoint(TTS, SPEECH_TYPE)]
    obs.nodes += [SLAM, COCO, TTS]
    obs.local_hashes.update(STACK_UPSTREAM_HASHES)
    obs.tf = {("odom", "base_link"): 60, ("map", "odom"): 150}
    obs.tf_static = {("base_link", "front_camera")}
    obs.map_frames = ["map"]
    obs.detection_receipts = [i * 0.25 for i in range(12)]
    obs.detection_classes = ["chair", "person", "chair"]
    obs.camera_infos = [(1280, 720, 900.0)]
    obs.root_webrtc_subscribed = True
    for key, value in changes.items():
        setattr(obs, key, value)
    return obs


def lines(obs: Observation) -> list[str]:
    return [str(f) for f in stack_findings(obs)]


def test_the_whole_stack_is_named_part_by_part() -> None:
    found = lines(stack())
    assert found == [
        "ok   odom -> base_link on /tf: 60 in 3 s; /tf from /go2_driver_node, /slam_toolbox",
        "ok   map -> odom on /tf: 150 in 3 s (SLAM's correction of odometry's drift: "
        "slam_toolbox, or a localization such as AMCL)",
        "ok   map on /map in frame map, and TF gives map -> odom",
        "ok   detections on /detected_objects from /coco_detector_node: 12 arrays in 3 s, "
        "4.0 Hz, 3 boxes: chair (2), person (1)",
        "ok   camera model on /camera/camera_info from /go2_driver_node: 1280 x 720, fx 900 px",
        "ok   speech on /tts reaches /tts_node",
    ], found
    assert [str(f) for f in diagnose(stack())][-6:] == found  # after the driver's own


def test_missing_optional_parts_are_info_or_warnings_never_failures() -> None:
    """Every combination of parts missing: the doctor's exit code is the driver's alone."""
    parts = {
        "tf": dict(tf={}, tf_static=set()),
        "slam": dict(tf={("odom", "base_link"): 60}),
        "map": dict(map_frames=[]),
        "detector": dict(detection_receipts=[], detection_classes=[]),
        "camera_info": dict(camera_infos=[]),
        "tts": dict(nodes=[DRIVER]),
    }
    for n in range(len(parts) + 1):
        for gone in itertools.combinations(parts, n):
            obs = stack()
            for part in gone:
                for key, value in parts[part].items():
                    setattr(obs, key, value)
            if "tf" in gone:
                obs.publishers["tf"] = []
            if "map" in gone:
                obs.publishers["map"] = []
            if "detector" in gone:
                obs.publishers["coco_detections"] = []
            if "camera_info" in gone:
                obs.publishers["camera_info"] = []
            if "tts" in gone:
                obs.subscribers["speech"] = []
            levels = {f.level for f in stack_findings(obs)}
            assert levels <= {"ok", "info", "warn"}, (gone, lines(obs))
    bare = lines(
        stack(
            tf={},
            tf_static=set(),
            publishers={},
            subscribers={},
            nodes=[],
            map_frames=[],
            detection_receipts=[],
            camera_infos=[],
        )
    )
    assert [line.split(" ", 1)[0] for line in bare] == ["warn", "info", "info", "info"], bare
    assert bare[0].startswith("warn nothing publishes /tf: no odom -> base_link"), bare
    assert bare[1].startswith("info nothing publishes /map: no map (slam_toolbox or map_server)")
    assert bare[2].startswith("info nothing publishes /detected_objects: no object detector")
    assert "ros2 run coco_detector coco_detector_node" in bare[2]
    assert "-p coco_detections_topic:=detected_objects" in bare[2]
    assert bare[3].startswith("info nothing subscribes /tts: the robot does not speak aloud")
    assert "ELEVENLABS_API_KEY" in bare[3]


def test_a_map_in_the_map_frame_needs_slams_map_to_odom() -> None:
    found = lines(stack(tf={("odom", "base_link"): 60}))
    assert found[1].startswith("info no map -> odom on /tf: no SLAM or localization running")
    assert found[2].startswith(
        "warn the map on /map is in frame 'map', but nothing publishes map -> odom on /tf"
    ), found
    assert "run slam_toolbox (it publishes the map and map -> odom)" in found[2]
    # A fixed map -> odom (a static transform publisher beside map_server) places it too.
    fixed = lines(stack(tf={("odom", "base_link"): 60}, tf_static={("map", "odom")}))
    assert fixed[1] == "ok   map -> odom on /tf_static: a fixed transform (no SLAM corrections)"
    assert fixed[2] == "ok   map on /map in frame map, and TF gives map -> odom"
    # A map in odom (map_server with frame_id odom, the sim-driver) needs no transform.
    in_odom = lines(stack(tf={("odom", "base_link"): 60}, map_frames=["odom"]))
    assert in_odom[2].startswith("ok   map on /map in frame odom: the map and odometry's poses")
    waiting = lines(stack(map_frames=[]))
    assert waiting[2].startswith("warn /slam_toolbox publishes /map, but no map arrived in 3 s"), (
        waiting
    )
    assert "transient local" in waiting[2]


def test_without_odom_to_base_link_the_transforms_seen_are_named() -> None:
    found = lines(stack(tf={("map", "odom"): 150}))
    assert found[0].startswith(
        "warn no odom -> base_link on /tf in 3 s (transforms seen: map -> odom)"
    ), found
    assert "odom -> robot{i}/base_link (--namespace robot{i})" in found[0]
    static = lines(stack(tf={("map", "odom"): 150}, tf_static={("odom", "base_link")}))
    assert static[0].startswith("warn odom -> base_link is on /tf_static: a fixed transform")


def test_several_robots_have_their_base_link_under_their_names() -> None:
    """go2_ros2_sdk with several ROBOT_IPs: odom -> robot0/base_link."""
    prefixed = {("odom", "robot0/base_link"): 60, ("odom", "robot1/base_link"): 60}
    found = lines(stack(namespace="robot0", tf=prefixed))
    assert found[0].startswith("ok   odom -> robot0/base_link on /tf: 60 in 3 s"), found
    # A namespaced driver whose frames are not prefixed (a ROS namespace, one robot).
    plain = lines(stack(namespace="late", tf={("odom", "base_link"): 40}))
    assert plain[0].startswith("ok   odom -> base_link on /tf: 40 in 3 s"), plain


def test_tf_that_cannot_be_read_or_differs_is_a_warning() -> None:
    found = lines(stack(unreadable={"tf": "No module named 'tf2_msgs'"}))
    assert found == [
        "warn /go2_driver_node, /slam_toolbox publishes /tf, but this Python cannot read "
        "tf2_msgs (No module named 'tf2_msgs')\n"
        "     fix: run scripts/build_ros.sh (it builds tf2_msgs where none is importable)",
        *found[1:],
    ]
    stale = "RIHS01_" + "1" * 64
    differ = lines(stack(local_hashes={**STACK_UPSTREAM_HASHES, TF_TYPE: stale}))
    assert "DDS drops every sample" in differ[0] and differ[0].startswith("warn /tf: "), differ


def test_a_detector_that_is_there_but_cannot_work_is_a_warning() -> None:
    wrong = stack()
    wrong.publishers["coco_detections"] = [
        Endpoint("/bridge", "shadowhound_interfaces/msg/DetectionArray")
    ]
    found = next(line for line in lines(wrong) if "/detected_objects" in line)
    assert found.startswith(
        "warn /detected_objects has type shadowhound_interfaces/msg/DetectionArray, expected "
        "vision_msgs/msg/Detection2DArray"
    ), found
    assert "goes to detections_topic" in found
    stale = "RIHS01_" + "2" * 64
    differ = lines(stack(local_hashes={**STACK_UPSTREAM_HASHES, DETECTIONS_TYPE: stale}))
    assert any(
        line.startswith("warn /detected_objects: /coco_detector_node's") and "DDS drops" in line
        for line in differ
    ), differ
    ours = lines(stack(local_hashes={TF_TYPE: STACK_UPSTREAM_HASHES[TF_TYPE]}))
    assert not any("is not ROS 2 Jazzy's" in line for line in ours)  # no local hash: no claim
    old_copy = lines(
        stack(local_hashes={**STACK_UPSTREAM_HASHES, DETECTIONS_TYPE: stale}, publishers={})
    )
    assert not any("Jazzy's" in line for line in old_copy)  # nothing on the topic: no claim
    silent = lines(stack(detection_receipts=[], detection_classes=[]))
    line = next(x for x in silent if "/detected_objects" in x)
    assert line.startswith(
        "warn /coco_detector_node publishes /detected_objects, but no detections arrived in 3 s"
    ), line
    assert "/camera/image_raw:=/robot0/camera/image_raw" in line
    unread = lines(stack(unreadable={"coco_detections": "No module named 'vision_msgs'"}))
    assert any("cannot read vision_msgs" in x and "scripts/build_ros.sh" in x for x in unread)
    empty = lines(stack(detection_classes=[]))
    assert any(x.endswith("12 arrays in 3 s, 4.0 Hz, 0 boxes: nothing in view") for x in empty)


def test_the_camera_model_matters_only_with_a_detector() -> None:
    none = stack(camera_infos=[])
    none.publishers["camera_info"] = []
    found = lines(none)
    assert any(
        line.startswith("warn nothing publishes /camera/camera_info: without the camera model")
        for line in found
    ), found
    no_focal = lines(stack(camera_infos=[(1280, 720, 0.0)]))
    assert any(
        x.startswith("warn camera_info on /camera/camera_info has no focal length")
        for x in no_focal
    )
    silent = lines(stack(camera_infos=[]))
    assert any(
        x.startswith("warn /go2_driver_node publishes /camera/camera_info, but no camera_info")
        for x in silent
    )
    alone = stack(camera_infos=[])
    alone.publishers["coco_detections"], alone.publishers["camera_info"] = [], []
    assert not any("camera_info" in line for line in lines(alone))


def test_a_tts_node_that_does_not_listen_is_told_its_key_is_missing() -> None:
    """tts_node subscribes /tts only once its provider starts: without ELEVENLABS_API_KEY it is
    up and deaf."""
    obs = stack()
    obs.subscribers["speech"] = []
    found = lines(obs)[-1]
    assert found.startswith(
        "warn /tts_node is up but does not subscribe /tts: it subscribes only once its "
        "text-to-speech provider starts (no ELEVENLABS_API_KEY?)"
    ), found
    assert "export ELEVENLABS_API_KEY" in found
    wrong = stack()
    wrong.subscribers["speech"] = [Endpoint("/speaker", "audio_msgs/msg/Text")]
    assert lines(wrong)[-1].startswith(
        "warn /tts has type audio_msgs/msg/Text, expected std_msgs/msg/String"
    )


def test_with_robot_names_tts_nodes_audio_reaches_no_driver() -> None:
    """tts_node sends the audio on the absolute /webrtc_req; a driver of several robots listens
    on robot{i}/webrtc_req."""
    obs = stack(namespace="robot0", root_webrtc_subscribed=False)
    found = lines(obs)[-1]
    assert found.startswith(
        "warn speech on /tts reaches /tts_node, but tts_node sends the audio on /webrtc_req, "
        "which nothing subscribes (the driver of robot0 listens on /robot0/webrtc_req)"
    ), found
    assert "-r /webrtc_req:=/robot0/webrtc_req" in found
    heard = lines(stack(namespace="robot0", root_webrtc_subscribed=True))[-1]
    assert heard == "ok   speech on /tts reaches /tts_node"


def test_a_topic_left_empty_is_not_checked() -> None:
    found = lines(stack(coco_detections_topic="", speech_topic="", map_topic=""))
    assert len(found) == 2 and all("/tf" in line for line in found), found
