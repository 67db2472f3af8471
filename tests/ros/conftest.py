"""ROS 2 tests: DDS stays on this machine, in a domain of its own.

The environment is set here, before any test module imports rclpy, and child processes
inherit it: loopback + shared-memory Fast DDS profile (shipped in shadowhound/ros/),
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, and a ROS_DOMAIN_ID this process holds alone among
the test processes on this machine (`claim_domain`): each pytest-xdist worker, and every
other test run at the same time, gets its own. Two runs in one domain answer each other's
tests (seen: a run's nav2 rig got another run's node's status lines).
"""

from __future__ import annotations

import os
import random

from shadowhound.ros.dds import LOCKS, claim_domain, loopback_env

__all__ = ["DOMAIN", "LOCKS", "claim_domain"]

# From a random domain on: runs started together have neighbouring pids, and a run that takes
# no lock (an older checkout) uses the pid-derived domain, 1 + pid % 100.
DOMAIN, _HELD = claim_domain(random.randint(1, 100))
os.environ.update(loopback_env(DOMAIN))
