"""ROS 2 tests: DDS stays on this machine, in a domain of its own.

The environment is set here, before any test module imports rclpy, and child processes
inherit it: loopback + shared-memory Fast DDS profile (shipped in shadowhound/ros/),
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_DOMAIN_ID derived from the test run's process id
and, under pytest-xdist, the worker's number (tests_domain_id).
"""

from __future__ import annotations

import os
from collections.abc import Mapping

from shadowhound.ros.dds import loopback_env, session_domain_id

RUN_PID = "SHADOWHOUND_TESTS_RUN_PID"  # set by tests/conftest.py in the run's first process


def tests_domain_id(environ: Mapping[str, str] = os.environ) -> int:
    """This process's domain: the run's, plus the xdist worker's number (gw0, gw1, ...), so two
    workers of one run never share a domain (their own pids could, modulo 100)."""
    worker = environ.get("PYTEST_XDIST_WORKER", "gw0")
    return session_domain_id(int(environ.get(RUN_PID, os.getpid())), int(worker[2:]))


os.environ.update(loopback_env(tests_domain_id()))
