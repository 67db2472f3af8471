"""Robot backend tests: the ROS backends talk over DDS, so this directory keeps DDS on this
machine, in a domain of its own, exactly as tests/ros does: the setup is tests/ros/conftest.py's
(imported here, run once per process, whichever directory's tests come first)."""

from __future__ import annotations

from tests.ros.conftest import DOMAIN, LOCKS, claim_domain

__all__ = ["DOMAIN", "LOCKS", "claim_domain"]
