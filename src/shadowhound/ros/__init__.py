"""ROS 2 interface: `MissionNode` (alias `MissionAgentNode`) and `main` for `shadowhound node`.

Importing `shadowhound` or this package does not import rclpy; `shadowhound.ros.node` does
(install the `ros` extra and build the interfaces with scripts/build_ros.sh).
"""

from __future__ import annotations

from typing import Any

__all__ = ["MissionAgentNode", "MissionNode", "main"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from . import node

        return getattr(node, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
