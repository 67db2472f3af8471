"""`shadowhound doctor --go2`, the rest of a Go2 owner's stack: TF and SLAM's map, the object
detector and its camera model, and the robot's voice (docs/go2-stack.md). Pure rules over an
`Observation`.

These parts are optional: a mission runs without them, with less. So a part that is simply not
there is `info`, and `warn` is kept for a part that is there but cannot work (a wrong type, a
type hash DDS would drop, a publisher that sends nothing, a map no transform places); none of
them fails the doctor.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from ..robot.tf_tree import BASE, MAP, ODOM
from .go2_doctor_observation import Endpoint, Finding, Observation, topic_name

DETECTIONS_TYPE = "vision_msgs/msg/Detection2DArray"
CAMERA_INFO_TYPE = "sensor_msgs/msg/CameraInfo"
SPEECH_TYPE = "std_msgs/msg/String"
MAP_TYPE = "nav_msgs/msg/OccupancyGrid"
TF_TYPE = "tf2_msgs/msg/TFMessage"
# Upstream's type hashes (ROS 2 Jazzy; tests/ros/test_vision_msgs.py, test_tf2_msgs.py pin
# ShadowHound's shipped copies to them).
STACK_UPSTREAM_HASHES = {
    DETECTIONS_TYPE: "RIHS01_214274120007f4a683866481336b70310268cfa107aebe9d594a6acf75bda968",
    TF_TYPE: "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
}
TTS_NODE = "tts_node"  # go2_ros2_sdk's speech_processor, started by robot.launch.py
REBUILD = (
    "source the ROS workspace the other side runs from before starting ShadowHound, or "
    "rebuild ShadowHound's copy (scripts/build_ros.sh)"
)


def stack_findings(obs: Observation) -> list[Finding]:
    """TF and the map first (where things are), then what is seen, then the voice."""
    return [*_tf(obs), *_map(obs), *_detector(obs), *_camera_info(obs), *_speech(obs)]


def _nodes(ends: Sequence[Endpoint]) -> str:
    return ", ".join(sorted({e.node for e in ends}))


def _type_problem(
    obs: Observation, key: str, kind: str, ends: Sequence[Endpoint], fix: str = ""
) -> Finding | None:
    """A wrong type (`fix` says what to do), or this Python's type hash against the other
    side's and upstream's."""
    topic = topic_name(obs, key)
    wrong = sorted({e.type for e in ends if e.type != kind})
    if wrong:
        return Finding("warn", f"{topic} has type {', '.join(wrong)}, expected {kind}", fix)
    local = obs.local_hashes.get(kind, "")
    differ = sorted({e.hash for e in ends if e.hash and local and e.hash != local})
    if differ:
        return Finding(
            "warn",
            f"{topic}: {_nodes(ends)}'s {kind} (type hash {differ[0]}) is not the one "
            f"ShadowHound loaded ({local}); DDS drops every sample although the topic looks "
            "matched",
            REBUILD,
        )
    upstream = STACK_UPSTREAM_HASHES.get(kind)
    if ends and upstream and local and local != upstream:
        return Finding(
            "warn",
            f"this build's {kind} (type hash {local}) is not ROS 2 Jazzy's ({upstream})",
            "rebuild ShadowHound's copy (scripts/build_ros.sh) or install the ROS package",
        )
    return None


def _base_frame(obs: Observation) -> str:
    """The robot's base frame on TF: go2_ros2_sdk names it robot{i}/base_link with several
    robots (under the robot{i}/ names), else base_link."""
    prefixed = f"{obs.namespace}/{BASE}" if obs.namespace else BASE
    seen = {child for parent, child in [*obs.tf, *obs.tf_static] if parent == ODOM}
    return prefixed if prefixed in seen or BASE not in seen else BASE


def _tf(obs: Observation) -> list[Finding]:
    ends = obs.publishers.get("tf", [])
    problem = _type_problem(obs, "tf", TF_TYPE, ends)
    if problem:
        return [problem]
    if not ends and not obs.tf:
        return [
            Finding(
                "warn",
                "nothing publishes /tf: no odom -> base_link (go2_ros2_sdk's driver broadcasts "
                "it with each pose) and no map -> odom (slam_toolbox)",
                "start the driver as go2_ros2_sdk's robot.launch.py does (docs/go2-stack.md); "
                "Nav2, slam_toolbox and RViz place the robot through TF",
            )
        ]
    if "tf" in obs.unreadable:
        return [
            Finding(
                "warn",
                f"{_nodes(ends)} publishes /tf, but this Python cannot read tf2_msgs "
                f"({obs.unreadable['tf']})",
                "run scripts/build_ros.sh (it builds tf2_msgs where none is importable)",
            )
        ]
    seen = ", ".join(f"{p} -> {c}" for p, c in sorted(obs.tf)) or "none"
    by = f"; /tf from {_nodes(ends)}" if ends else ""
    out = []
    base = _base_frame(obs)
    if (ODOM, base) in obs.tf:
        count = obs.tf[(ODOM, base)]
        out.append(Finding("ok", f"odom -> {base} on /tf: {count} in {obs.seconds:.0f} s{by}"))
    elif (ODOM, base) in obs.tf_static:
        out.append(
            Finding(
                "warn",
                f"odom -> {base} is on /tf_static: a fixed transform, the robot never moves in TF",
                "odom -> base_link is the driver's, broadcast on /tf with each pose: stop the "
                "static transform publisher",
            )
        )
    else:
        out.append(
            Finding(
                "warn",
                f"no odom -> {base} on /tf in {obs.seconds:.0f} s (transforms seen: {seen})",
                "go2_ros2_sdk's driver broadcasts it with each odometry message: check the "
                "odometry above; with several robots it is odom -> robot{i}/base_link "
                "(--namespace robot{i})",
            )
        )
    if (MAP, ODOM) in obs.tf:
        out.append(
            Finding(
                "ok",
                f"map -> odom on /tf: {obs.tf[(MAP, ODOM)]} in {obs.seconds:.0f} s (SLAM's "
                "correction of odometry's drift: slam_toolbox, or a localization such as AMCL)",
            )
        )
    elif (MAP, ODOM) in obs.tf_static:
        out.append(
            Finding("ok", "map -> odom on /tf_static: a fixed transform (no SLAM corrections)")
        )
    else:
        out.append(
            Finding(
                "info",
                "no map -> odom on /tf: no SLAM or localization running; places and goals are "
                "in odom and drift with it",
                "go2_ros2_sdk's robot.launch.py starts slam_toolbox (unless slam:=false); it "
                "publishes map -> odom once scans arrive on /scan",
            )
        )
    return out


def _map(obs: Observation) -> list[Finding]:
    if not obs.map_topic:
        return []
    topic, ends = topic_name(obs, "map"), obs.publishers.get("map", [])
    problem = _type_problem(obs, "map", MAP_TYPE, ends)
    if problem:
        return [problem]
    if not obs.map_frames:
        if not ends:
            return [
                Finding(
                    "info",
                    f"nothing publishes {topic}: no map (slam_toolbox or map_server), so "
                    "ShadowHound's own paths are straight lines (Nav2 still plans on its "
                    "costmaps)",
                    "go2_ros2_sdk's robot.launch.py starts slam_toolbox (unless slam:=false), "
                    "or run map_server with a saved map",
                )
            ]
        return [
            Finding(
                "warn",
                f"{_nodes(ends)} publishes {topic}, but no map arrived in {obs.seconds:.0f} s",
                "slam_toolbox publishes its first map once scans arrive (check /scan: "
                "go2_pointcloud_to_laserscan makes it from point_cloud2). ShadowHound reads "
                "the map reliable + transient local, as slam_toolbox and map_server publish "
                "it: a volatile publisher does not match",
            )
        ]
    frame = obs.map_frames[-1].lstrip("/")
    if frame == ODOM:
        return [
            Finding(
                "ok",
                f"map on {topic} in frame odom: the map and odometry's poses agree without TF "
                "(map_server with frame_id odom, or shadowhound sim-driver)",
            )
        ]
    if not frame:
        return [
            Finding(
                "warn",
                f"the map on {topic} has no frame_id",
                "publish it in map (with SLAM's map -> odom) or in odom",
            )
        ]
    if (frame, ODOM) in obs.tf or (frame, ODOM) in obs.tf_static:
        return [Finding("ok", f"map on {topic} in frame {frame}, and TF gives {frame} -> odom")]
    return [
        Finding(
            "warn",
            f"the map on {topic} is in frame {frame!r}, but nothing publishes {frame} -> odom on "
            "/tf: the map cannot be placed against odometry",
            "run slam_toolbox (it publishes the map and map -> odom) or a localization such as "
            "AMCL beside map_server; else publish the map in odom",
        )
    ]


def _detector(obs: Observation) -> list[Finding]:
    if not obs.coco_detections_topic:
        return []
    topic, ends = topic_name(obs, "coco_detections"), obs.publishers.get("coco_detections", [])
    if not ends:
        return [
            Finding(
                "info",
                f'nothing publishes {topic}: no object detector, so "go to the chair" cannot '
                "find a chair",
                "start go2_ros2_sdk's coco_detector beside the launch (ros2 run coco_detector "
                "coco_detector_node; it reads /camera/image_raw) and run ShadowHound's node "
                "with -p coco_detections_topic:=detected_objects",
            )
        ]
    problem = _type_problem(
        obs,
        "coco_detections",
        DETECTIONS_TYPE,
        ends,
        "coco_detections_topic takes vision_msgs/Detection2DArray "
        "(shadowhound_interfaces/DetectionArray goes to detections_topic)",
    )
    if problem:
        return [problem]
    if "coco_detections" in obs.unreadable:
        return [
            Finding(
                "warn",
                f"{_nodes(ends)} publishes {topic}, but this Python cannot read vision_msgs "
                f"({obs.unreadable['coco_detections']})",
                "run scripts/build_ros.sh (it builds vision_msgs where none is importable)",
            )
        ]
    times = obs.detection_receipts
    if not times:
        return [
            Finding(
                "warn",
                f"{_nodes(ends)} publishes {topic}, but no detections arrived in "
                f"{obs.seconds:.0f} s (coco_detector publishes one array per camera image)",
                "check the camera: coco_detector reads /camera/image_raw, that absolute name "
                "(with robot{i}/ names remap it: --ros-args -r "
                "/camera/image_raw:=/robot0/camera/image_raw)",
            )
        ]
    counts = Counter(obs.detection_classes)
    boxes = (
        ", ".join(f"{name} ({n})" for name, n in counts.most_common(6))
        if counts
        else "nothing in view"
    )
    span = times[-1] - times[0]
    rate = f", {(len(times) - 1) / span:.1f} Hz" if span > 0 else ""
    arrays = f"{len(times)} array{'s' if len(times) > 1 else ''}"
    found = len(obs.detection_classes)
    return [
        Finding(
            "ok",
            f"detections on {topic} from {_nodes(ends)}: {arrays} in {obs.seconds:.0f} s{rate}, "
            f"{found} box{'es' if found != 1 else ''}: {boxes}",
        )
    ]


def _camera_info(obs: Observation) -> list[Finding]:
    """The camera model the boxes need: a warning only when a detector publishes (without
    one, and without camera_info, nothing is said: the detector's finding comes first)."""
    if not obs.coco_detections_topic or not obs.camera_info_topic:
        return []
    topic, ends = topic_name(obs, "camera_info"), obs.publishers.get("camera_info", [])
    detecting = bool(obs.publishers.get("coco_detections"))
    problem = _type_problem(obs, "camera_info", CAMERA_INFO_TYPE, ends)
    if problem:
        return [problem]
    if obs.camera_infos:
        width, height, fx = obs.camera_infos[-1]
        if fx > 0:
            return [
                Finding(
                    "ok",
                    f"camera model on {topic} from {_nodes(ends)}: {width} x {height}, "
                    f"fx {fx:.0f} px",
                )
            ]
        return [
            Finding(
                "warn",
                f"camera_info on {topic} has no focal length (K[0] = {fx:g}): boxes cannot "
                "become bearings",
                "publish the camera's calibration (go2_ros2_sdk's driver reads "
                "calibration/front_camera_720.yaml)",
            )
        ]
    if ends:
        return [
            Finding(
                "warn" if detecting else "info",
                f"{_nodes(ends)} publishes {topic}, but no camera_info arrived in "
                f"{obs.seconds:.0f} s",
                "go2_ros2_sdk's driver publishes it with each camera image (best effort): "
                "check the camera",
            )
        ]
    if not detecting:
        return []  # the detector's own finding says what to start first
    return [
        Finding(
            "warn",
            f"nothing publishes {topic}: without the camera model, boxes cannot become bearings",
            "go2_ros2_sdk's driver publishes camera/camera_info with its camera images; "
            "camera_info_topic names another",
        )
    ]


def _speech(obs: Observation) -> list[Finding]:
    if not obs.speech_topic:
        return []
    topic, ends = topic_name(obs, "speech"), obs.subscribers.get("speech", [])
    wrong = sorted({e.type for e in ends if e.type != SPEECH_TYPE})
    listeners = [e for e in ends if e.type == SPEECH_TYPE]
    tts = sorted(n for n in obs.nodes if n.rsplit("/", 1)[-1] == TTS_NODE)
    if wrong and not listeners:
        return [
            Finding(
                "warn",
                f"{topic} has type {', '.join(wrong)}, expected {SPEECH_TYPE}",
                "speech_topic takes std_msgs/String, one message per saying",
            )
        ]
    if listeners:
        text = f"speech on {topic} reaches {_nodes(listeners)}"
        if obs.namespace and tts and not obs.root_webrtc_subscribed:
            return [
                Finding(
                    "warn",
                    text + f", but {TTS_NODE} sends the audio on /webrtc_req, which nothing "
                    f"subscribes (the driver of {obs.namespace} listens on "
                    f"/{obs.namespace}/webrtc_req)",
                    f"remap it: --ros-args -r /webrtc_req:=/{obs.namespace}/webrtc_req",
                )
            ]
        return [Finding("ok", text)]
    if tts:
        return [
            Finding(
                "warn",
                f"{', '.join(tts)} is up but does not subscribe {topic}: it subscribes only "
                "once its text-to-speech provider starts (no ELEVENLABS_API_KEY?)",
                "export ELEVENLABS_API_KEY before ros2 launch go2_robot_sdk robot.launch.py "
                "(tts_node's log says 'ElevenLabs API key not provided!')",
            )
        ]
    return [
        Finding(
            "info",
            f"nothing subscribes {topic}: the robot does not speak aloud (the dashboard and "
            "the mission's answer still show the words)",
            "go2_ros2_sdk's robot.launch.py starts tts_node (speech_processor), which needs "
            "ELEVENLABS_API_KEY; speech_topic:='' stops publishing them",
        )
    ]
