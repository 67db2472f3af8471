"""Keeping DDS traffic on this machine (tests, benchmarks, a laptop demo).

`loopback_env()` returns the environment a process needs so that ROS 2 discovery and data
stay on loopback and shared memory: a Fast DDS profile that allows only those transports,
`ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` and a domain id. Set it before rclpy is imported and
pass it to child processes. `claim_domain()` finds a domain no other test or benchmark process
on this machine holds. No rclpy import here.
"""

from __future__ import annotations

import os
import random
import tempfile
from pathlib import Path
from typing import IO

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


LOCKS = Path(tempfile.gettempdir())


def claim_domain(start: int | None = None, locks: Path = LOCKS) -> tuple[int, IO[str]]:
    """The first domain from `start` (default: a random one) on, 1..100 wrapping, that no other
    process holds: a lock on a file per domain, held as long as the returned file stays open
    (this process's life). Tests and benchmarks that run at the same time each claim one:
    derived from a pid alone, domains collided and one run's nodes answered the other's
    (a benchmark's agent read another run's odometry)."""
    import fcntl  # POSIX only, and only here

    first = random.randint(1, 100) if start is None else start
    for step in range(100):
        domain = 1 + (first - 1 + step) % 100
        lock = (locks / f"shadowhound-test-ros-domain-{domain}.lock").open("w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        return domain, lock
    raise RuntimeError("every ROS domain 1..100 is held by another test or benchmark process")
