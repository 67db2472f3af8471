"""Keeping DDS traffic on this machine (tests, benchmarks, a laptop demo).

`loopback_env()` returns the environment a process needs so that ROS 2 discovery and data
stay on loopback and shared memory: a Fast DDS profile that allows only those transports,
`ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` and a domain id. Set it before rclpy is imported and
pass it to child processes. No rclpy import here.
"""

from __future__ import annotations

import os
from pathlib import Path

LOOPBACK_PROFILE = Path(__file__).with_name("fastdds_loopback.xml")


def session_domain_id(pid: int | None = None) -> int:
    """A domain id in 1..100 derived from a process id, so parallel sessions do not meet."""
    return 1 + (os.getpid() if pid is None else pid) % 100


def loopback_env(domain_id: int | None = None) -> dict[str, str]:
    """Environment variables that keep ROS 2 (Fast DDS) on this machine."""
    domain = session_domain_id() if domain_id is None else domain_id
    if not 0 <= domain <= 232:
        raise ValueError(f"ROS_DOMAIN_ID must be in 0..232, got {domain}")
    profile = str(LOOPBACK_PROFILE)
    return {
        "ROS_DOMAIN_ID": str(domain),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        "FASTRTPS_DEFAULT_PROFILES_FILE": profile,
        "FASTDDS_DEFAULT_PROFILES_FILE": profile,
    }
