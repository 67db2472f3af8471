"""`shadowhound sim-driver`: a simulated Go2 behind go2_ros2_sdk's topics, as the real driver
behaves (read from its source; see docs/go2.md), backed by SimRobots in real time.

Per robot (names prefixed `robot{i}/` with `--robots 2` or more, as go2_ros2_sdk does):
- `cmd_vel_out` (geometry_msgs/Twist) in: an all-zero Twist is dropped; any other becomes a
  Move rounded to 2 decimals, sent at once; the robot runs it until it lapses
  (`--move-timeout`) or StopMove arrives. `cmd_vel` reaches it only through the twist_mux-like
  relay (ros/twist_mux.py; on unless `--no-relay`; not namespaced, so it feeds `cmd_vel_out`);
- `webrtc_req` (go2_interfaces/WebRtcReq) in: `parameter` must be '' or JSON (else dropped),
  an empty `topic` means the sport topic, `id` and `priority` are ignored; requests are
  queued and handed to the robot by a 10 Hz loop;
- `odom` out: pose only (the twist stays zero), at `--odom-rate-hz`, each the true pose of
  `--odom-delay` seconds before (drifting by `--odom-drift`), stamped when published; frames
  odom -> base_link, also broadcast on `/tf` (tf2_msgs/TFMessage) as the driver does; with
  `--slam` (one robot), as slam_toolbox: `map -> odom` on `/tf` with each odometry sample (the
  correction that takes the drifting odometry onto the truth), the map in frame `map`, the
  detections in `map` and Nav2 goals in `odom` carried into the map;
- `go2_states` out: mode per posture, `progress` only for tricks, velocity (odom frame) and
  body height from the truth; `camera/image_raw` out (best effort);
- `battery_state` (sensor_msgs/BatteryState) out only with `--battery PERCENT`;
- `scan` (sensor_msgs/LaserScan: 360 beams, 0.1-8 m, `--scan-rate-hz`, from the simulator's ray
  casting, frame base_link) out; `map` (nav_msgs/OccupancyGrid: the scene at 5 cm, frame odom,
  transient local as map_server publishes it) out once;
- `detections` (shadowhound_interfaces/DetectionArray) out at 2 Hz with `--detector shadowhound`:
  the objects the simulated camera sees (field of view and occlusion), at their true centres in
  frame odom, confidence 1, true radius: a detector for `detections_topic` of the Go2 robot;
  with `--detector coco` instead `detected_objects` (vision_msgs/Detection2DArray: each object's
  box in the camera image under its COCO name, as go2_ros2_sdk's coco_detector) and
  `camera/camera_info` (best effort), for `coco_detections_topic`; `--detector none`: neither;
- `navigate_to_pose` (nav2_msgs/action/NavigateToPose) served with the project's planner and
  path follower (ros/sim_nav.py), unless `--no-navigate-to-pose`;
- `sim_driver/truth` (std_msgs/String JSON) out: the ground truth (true pose, velocity,
  posture, mode, counts of Moves and StopMoves received ...), kept apart from what the driver
  publishes; `sim_driver/requests` out: one JSON record per sport request; `sim_driver/fault`
  in: fault injection ({"odom": false}, {"states": false}, {"camera": false},
  {"delay_ms": 200}, {"drop_commands": true}, {"stall_ms": 400}; {} clears them).

With `--interface unitree_ros2` the robots speak Unitree's own interface instead (a Go2 EDU;
sim_driver/unitree.py): `api/sport/request` in, `api/sport/response`, `lf/sportmodestate` and
`lf/lowstate` out, besides `sim_driver/*`; none of go2_ros2_sdk's topics, relay or servers.
There the sport state carries the pose, so the `odom` fault stops it (as `states` does).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node

from ..config import SimConfig
from ..errors import ParameterError
from ..robot.go2.api import SportMode
from ..robot.sim.robot import SimRobot
from ..ros.process import run_node
from .go2 import Faults, SimGo2, Truth
from .options import (
    DETECTIONS_RATE_HZ,
    OPTIONS,
    DriverSettings,
    build_parser,
    parse_settings,
    split_argv,
)
from .twist_mux import TwistMux

__all__ = ["Faults", "SimDriver", "Truth", "main"]

NODE_NAME = "shadowhound_sim_driver"
# Modes a robot may report standing after StandUp (sim_options' stand_up_mode).
STAND_UP_MODES = (
    SportMode.IDLE,
    SportMode.BALANCE_STAND,
    SportMode.JOINT_LOCK,
    SportMode.DAMPING,
)
PROG = "shadowhound sim-driver"


class SimDriver(Node):
    """The simulated driver node. `options` override its ROS parameters (names as in
    sim_options.OPTIONS); give `sim` to drive an existing SimRobot (one robot only)."""

    def __init__(
        self,
        sim: SimRobot | None = None,
        *,
        options: Mapping[str, Any] | None = None,
        node_name: str = NODE_NAME,
        **node_kwargs: Any,
    ) -> None:
        super().__init__(node_name, **node_kwargs)
        self.settings = s = parse_settings({**self._read_parameters(), **(options or {})})
        if s.stand_up_mode not in STAND_UP_MODES:
            raise ParameterError(
                f"stand_up_mode must be one of {', '.join(map(str, STAND_UP_MODES))} (modes "
                f"of a robot standing still), got {s.stand_up_mode}"
            )
        if sim is not None and s.robots != 1:
            raise ParameterError("a given SimRobot makes one robot; robots must be 1")
        self.robots = [
            SimGo2(self, s, f"robot{i}/" if s.robots > 1 else "", sim or self._new_sim(s))
            for i in range(s.robots)
        ]
        self.relay = (
            TwistMux(s.relay_timeout, context=self.context, namespace=self.get_namespace())
            if s.relay
            else None
        )
        first = self.robots[0]
        self.create_timer(0.1, self._forward_requests)  # the driver's 10 Hz request loop
        self.create_timer(1.0 / s.state_rate_hz, self._each("publish_state"))
        self.create_timer(1.0 / s.truth_rate_hz, self._each("publish_truth"))
        if s.camera_rate_hz > 0:
            self.create_timer(1.0 / s.camera_rate_hz, self._each("publish_camera"))
        if s.battery is not None or first.unitree is not None:
            self.create_timer(1.0, self._each("publish_battery"))
        if s.scan_rate_hz > 0:
            self.create_timer(1.0 / s.scan_rate_hz, self._each("publish_scan"))
        if s.detector != "none":
            self.create_timer(1.0 / DETECTIONS_RATE_HZ, self._each("publish_detections"))
        for robot in self.robots:
            robot.start()
        if first.unitree is not None:
            self.get_logger().info(
                f"simulated Go2 EDU x{s.robots} (unitree_ros2) ready: "
                f"{first.unitree.request_topic} in; {first.topic('lf/sportmodestate')} "
                f"{s.state_rate_hz:g} Hz {s.odom_delay:g} s late, {first.topic('lf/lowstate')} "
                f"1 Hz out; truth on {first.topic('sim_driver/truth')}"
            )
            return
        self.get_logger().info(
            f"simulated Go2 x{s.robots} ready: {first.topic('cmd_vel_out')} and "
            f"{first.topic('webrtc_req')} in"
            + (f" ({self.relay.resolve_topic_name('cmd_vel')} relayed)" if self.relay else "")
            + f"; odom {s.odom_rate_hz:g} Hz {s.odom_delay:g} s late, go2_states "
            f"{s.state_rate_hz:g} Hz; battery "
            + ("none" if s.battery is None else f"{s.battery:g}% on {s.battery_topic}")
            + f"; truth on {first.topic('sim_driver/truth')}"
        )

    @property
    def nodes(self) -> list[Node]:
        """This node and the relay (if any): what an executor must spin."""
        return [self, *([self.relay] if self.relay else [])]

    @property
    def sim(self) -> SimRobot:
        """The (first) robot's simulator."""
        return self.robots[0].sim

    def truth(self, robot: int = 0) -> Truth:
        """Ground truth of robot `robot`, for in-process tests."""
        return self.robots[robot].body.truth()

    def truth_dict(self, robot: int = 0) -> dict[str, Any]:
        """The ground truth as published on sim_driver/truth."""
        return self.robots[robot].truth_dict()

    def close(self) -> None:
        """Stop every robot and the worker threads."""
        for robot in self.robots:
            robot.close()

    def destroy_node(self) -> None:
        if self.relay is not None:
            self.relay.destroy_node()
        super().destroy_node()

    def _new_sim(self, s: DriverSettings) -> SimRobot:
        return SimRobot(
            SimConfig(time_scale=1.0, battery_drain_idle=s.battery_drain), name="sim-driver"
        )

    def _read_parameters(self) -> dict[str, Any]:
        given = set(getattr(self, "_parameter_overrides", {})) - {"use_sim_time"}
        unknown = sorted(given - set(OPTIONS))
        if unknown:
            raise ParameterError(
                f"unknown ROS parameter(s): {', '.join(unknown)}; known: {', '.join(OPTIONS)}"
            )
        declared = {
            name: self.declare_parameter(
                name,
                getattr(DriverSettings(), name),
                ParameterDescriptor(description=option.help, dynamic_typing=True),
            ).value
            for name, option in OPTIONS.items()
        }  # all declared, so `ros2 param` lists them
        return {name: declared[name] for name in given}  # only those set win over defaults

    def _each(self, method: str) -> Any:
        return lambda: [getattr(robot, method)() for robot in self.robots]

    def _forward_requests(self) -> None:
        for robot in self.robots:
            robot.forward_requests()


_DESCRIPTION = f"""A simulated Unitree Go2 behind go2_ros2_sdk's ROS 2 topics, behaving as the real
driver does, as the ROS 2 node '{NODE_NAME}' (plus 'twist_mux', the relay). Run a mission on
it with `shadowhound node --ros-args -p robot:=go2` in another terminal.

Topics per robot (robot{{i}}/ prefix with --robots 2+): cmd_vel_out, webrtc_req in; odom (no
twist, late by --odom-delay), go2_states, camera/image_raw, battery_state (--battery only)
out; scan (LaserScan), map (OccupancyGrid, transient local) out; detections (DetectionArray,
{DETECTIONS_RATE_HZ:g} Hz: what the simulated camera sees; --detector coco: detected_objects,
vision_msgs/Detection2DArray boxes, and camera/camera_info instead; --detector none: none) out;
navigate_to_pose (Nav2's NavigateToPose action, served with the project's planner;
--no-navigate-to-pose: none);
sim_driver/truth (JSON ground truth), sim_driver/requests (JSON per sport request) out;
sim_driver/fault in. The relay: cmd_vel, cmd_vel_joy in, cmd_vel_out out.

--interface unitree_ros2: a Go2 EDU behind Unitree's unitree_ros2 instead (run a mission with
-p robot:=go2_edu): api/sport/request (unitree_api/Request) in; api/sport/response,
lf/sportmodestate (unitree_go/SportModeState), lf/lowstate (unitree_go/LowState) out; the
sim_driver/ topics as above; nothing of go2_ros2_sdk's.

Every option is also a ROS parameter with the same name in snake case (--ros-args -p
odom_delay:=0.5); an option given here wins. -r __ns:=/NS moves every topic, the relay's too."""
_EPILOG = """faults: publish JSON on sim_driver/fault, e.g. '{"odom": false}', '{"delay_ms": 200}',
'{"drop_commands": true}'; SLAM mislocalized (--slam): '{"slam_error": {"x": 0.5, "y": 0}}';
odometry that lies: '{"jump": {"x": -0.5, "y": 0, "yaw_deg": 0}}',
'{"freeze": true}', '{"nan": 3}', '{"clock_step": -2}', and '{"fall": true}'; a loaded machine:
'{"stall_ms": 400}'; each firing at once or after "after_m" metres / "after_deg" degrees of true
motion; '{}' clears them (docs/go2.md).
exit codes: 0 after Ctrl-C / SIGTERM, 2 for invalid options or parameters."""


def main(argv: Sequence[str] | None = None) -> int:
    """`shadowhound sim-driver [options] [--ros-args ...]`"""
    own, ros_args = split_argv(sys.argv[1:] if argv is None else argv)
    parser = build_parser(PROG, _DESCRIPTION, _EPILOG)
    options = vars(parser.parse_args(own))  # exits 2 with a message on bad options
    return run_node(
        PROG,
        NODE_NAME,
        ros_args,
        parser.format_help(),
        lambda: SimDriver(options=options),
        _close,
        "shutting down: the simulated robots stop",
        extra_nodes=_relay,
    )


def _close(driver: Node) -> None:
    assert isinstance(driver, SimDriver)
    driver.close()


def _relay(driver: Node) -> list[Node]:
    assert isinstance(driver, SimDriver)
    return driver.nodes[1:]


if __name__ == "__main__":
    sys.exit(main())
