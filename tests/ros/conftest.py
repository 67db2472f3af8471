"""ROS 2 tests: DDS stays on this machine, in a domain of its own.

The environment is set here, before any test module imports rclpy, and child processes
inherit it: loopback + shared-memory Fast DDS profile (shipped in shadowhound/ros/),
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_DOMAIN_ID derived from this process id.
"""

from __future__ import annotations

import os

from shadowhound.ros.dds import loopback_env

os.environ.update(loopback_env())
