"""The world's ROS messages: nav_msgs/OccupancyGrid <-> the core's grid, sensor_msgs/LaserScan
<-> the core's Scan, and the QoS map_server uses for `map`.

A map is read with its frame, origin (position and yaw) and resolution as published; cells keep
nav_msgs' layout, so nothing is reinterpreted (see world/grid.py).
"""

from __future__ import annotations

import array
import math
from typing import Any

from nav_msgs.msg import OccupancyGrid as GridMsg
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan

from ...state import Pose2D, Scan
from ...world.grid import OccupancyGrid
from ..input_limits import MAX_BEAMS

# map_server and slam_toolbox publish `map` reliable and transient-local (a late subscriber
# still gets the last map), depth 1.
MAP_QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


def grid_to_msg(grid: OccupancyGrid, frame_id: str, stamp: Any) -> GridMsg:
    """The grid as nav_msgs/OccupancyGrid in `frame_id`, stamped `stamp` (a Time message)."""
    msg = GridMsg()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    msg.info.map_load_time = stamp
    msg.info.resolution = float(grid.resolution)
    msg.info.width, msg.info.height = grid.width, grid.height
    msg.info.origin.position.x, msg.info.origin.position.y = grid.origin.x, grid.origin.y
    msg.info.origin.orientation.z = math.sin(grid.origin.yaw / 2.0)
    msg.info.origin.orientation.w = math.cos(grid.origin.yaw / 2.0)
    msg.data = array.array("b", bytes(grid.cells))  # int8: unknown (255) reads as -1
    return msg


def grid_from_msg(msg: GridMsg) -> OccupancyGrid:
    """The core's grid from a nav_msgs/OccupancyGrid (its frame is the message header's).
    Raises GridError when the message is malformed (sizes that do not match, ...)."""
    info, o = msg.info, msg.info.origin
    q = o.orientation
    # The origin's yaw from its quaternion (a map lies in the plane: roll and pitch are 0).
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    data = msg.data
    raw = data.tobytes() if isinstance(data, array.array) else bytes(v & 0xFF for v in data)
    return OccupancyGrid.from_msg(
        {
            "info": {
                "width": int(info.width),
                "height": int(info.height),
                "resolution": _decimal(info.resolution),
                "origin": {
                    "position": {"x": o.position.x, "y": o.position.y},
                    "orientation": {"z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)},
                },
            },
            "data": raw,
        }
    )


def scan_to_msg(scan: Scan, frame_id: str, stamp: Any, scan_time: float) -> LaserScan:
    """sensor_msgs/LaserScan in the body's frame: beam angles relative to the robot's heading;
    no return reads +inf (REP-117)."""
    msg = LaserScan()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    n = len(scan.ranges)
    msg.angle_min = float(scan.angle_min)
    msg.angle_increment = float(scan.angle_increment)
    msg.angle_max = float(scan.angle_min + (n - 1) * scan.angle_increment)
    msg.time_increment = 0.0  # every beam at once (a simulated, not a spinning, sensor)
    msg.scan_time = float(scan_time)
    msg.range_min, msg.range_max = float(scan.range_min), float(scan.range_max)
    msg.ranges = array.array("f", scan.ranges)
    return msg


def scan_from_msg(msg: LaserScan, pose: Pose2D, stamp: float) -> Scan:
    """The core's Scan from a LaserScan taken at `pose` (odom frame: the robot's pose when it
    arrived; the sensor is taken to sit at the body's centre, facing forward). Raises
    ValueError when the message is not a usable scan, or has more than MAX_BEAMS ranges."""
    if len(msg.ranges) > MAX_BEAMS:
        raise ValueError(
            f"{len(msg.ranges)} ranges in one scan; at most {MAX_BEAMS} are read (a lidar's "
            "scan has a few thousand)"
        )
    return Scan(
        tuple(float(r) for r in msg.ranges),
        _decimal(msg.angle_min),
        _decimal(msg.angle_increment),
        _decimal(msg.range_min),
        _decimal(msg.range_max),
        pose,
        stamp,
    )


def _decimal(value: float) -> float:
    """A float32 field as the decimal its publisher meant (float32 holds about 7 digits:
    0.05 arrives as 0.05000000074505806)."""
    return float(f"{value:.7g}")
