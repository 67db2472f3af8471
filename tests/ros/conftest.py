"""ROS 2 tests: DDS stays on this machine, in a domain of its own.

The environment is set here, before any test module imports rclpy, and child processes
inherit it: loopback + shared-memory Fast DDS profile (shipped in shadowhound/ros/),
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, and a ROS_DOMAIN_ID this process holds alone among
the test processes on this machine (`claim_domain`): each pytest-xdist worker, and every
other test run at the same time, gets its own. Two runs in one domain answer each other's
tests (seen: a run's nav2 rig got another run's node's status lines).
"""

from __future__ import annotations

import fcntl
import os
import random
import tempfile
from pathlib import Path
from typing import IO

from shadowhound.ros.dds import loopback_env

LOCKS = Path(tempfile.gettempdir())


def claim_domain(start: int, locks: Path = LOCKS) -> tuple[int, IO[str]]:
    """The first domain from `start` on (1..100, wrapping) that no other process holds: a lock
    on a file per domain, held as long as the returned file stays open (this process's life).
    Derived from a pid alone, the domains of runs started together collided (pids are handed
    out in sequence) and one run's nodes answered the other's tests."""
    for step in range(100):
        domain = 1 + (start - 1 + step) % 100
        lock = (locks / f"shadowhound-test-ros-domain-{domain}.lock").open("w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        return domain, lock
    raise RuntimeError("every ROS domain 1..100 is held by another test process")


# From a random domain on: runs started together have neighbouring pids, and a run that takes
# no lock (an older checkout) uses the pid-derived domain, 1 + pid % 100.
DOMAIN, _HELD = claim_domain(random.randint(1, 100))
os.environ.update(loopback_env(DOMAIN))
