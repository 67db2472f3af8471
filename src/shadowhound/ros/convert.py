"""Converting between the agent's diagnostics and ROS message fields. Pure Python (no rclpy).

The node unpacks messages into plain values and calls these, so the rules (which diagnostic
level a status gets, what a status line says) are testable anywhere. Raw images become
CameraFrames in `shadowhound.camera` (`raw_image_frame`), which the Go2 robot also uses.
"""

from __future__ import annotations

from typing import Any

from .. import jsonout

# diagnostic_msgs/DiagnosticStatus levels
OK, WARN, ERROR, STALE = 0, 1, 2, 3
_LEVEL_OF_STATUS = {
    "idle": OK,
    "planning": OK,
    "executing": OK,
    "succeeded": OK,
    "failed": WARN,
    "stopped": WARN,
}


def diagnostic_level(diagnostics: dict[str, Any]) -> int:
    """OK while idle/planning/executing/succeeded, WARN after failed/stopped or while the
    battery level is unknown, ERROR on e-stop."""
    if diagnostics.get("estop"):
        return ERROR
    level = _LEVEL_OF_STATUS.get(str(diagnostics.get("status")), WARN)
    return max(level, WARN) if _battery_unknown(diagnostics) else level


def _battery_unknown(diagnostics: dict[str, Any]) -> bool:
    robot = diagnostics.get("robot") or {}
    return "battery" in robot and robot["battery"] is None


def diagnostic_message(diagnostics: dict[str, Any]) -> str:
    """One line for rqt_robot_monitor's message column."""
    if diagnostics.get("estop"):
        return "e-stop latched"
    status = str(diagnostics.get("status"))
    if status in ("executing", "planning") and diagnostics.get("current_skill"):
        return (
            f"{status} {diagnostics['current_skill']} (step {diagnostics.get('step')}/"
            f"{diagnostics.get('steps')})"
        )
    errors = diagnostics.get("errors") or []
    if status in ("failed", "stopped") and errors:
        return f"{status}: {errors[-1]}"
    return status + (
        "; battery level unknown (no battery source)" if _battery_unknown(diagnostics) else ""
    )


def diagnostic_values(
    diagnostics: dict[str, Any], extra: dict[str, Any] | None = None
) -> list[tuple[str, str]]:
    """Key-values of the agent's diagnostics as strings (what DiagnosticStatus carries)."""
    robot = diagnostics.get("robot") or {}
    errors = list(diagnostics.get("errors") or [])
    memory = diagnostics.get("memory") or {}
    values: dict[str, Any] = {
        "status": diagnostics.get("status"),
        "mission": diagnostics.get("mission") or "",
        "current_skill": diagnostics.get("current_skill") or "",
        "step": f"{diagnostics.get('step', 0)}/{diagnostics.get('steps', 0)}",
        "progress": f"{float(diagnostics.get('progress') or 0.0):.3f}",
        "errors": "; ".join(errors[-3:]),
        "error_count": len(errors),
        "backend": diagnostics.get("backend"),
        "estop": bool(diagnostics.get("estop")),
        "pose_x": _known(robot, "x"),
        "pose_y": _known(robot, "y"),
        "pose_yaw": _known(robot, "yaw"),
        "battery": "unknown" if _battery_unknown(diagnostics) else robot.get("battery"),
        "posture": robot.get("posture"),
        "moving": robot.get("moving"),
        "memory_recall": memory.get("recall"),  # "unavailable" when its store is broken
        "memory_problem": shorten(memory.get("recall_problem") or ""),
    }
    values.update(extra or {})
    return [(k, _text(v)) for k, v in values.items()]


def _known(robot: dict[str, Any], key: str) -> Any:
    """A number of the robot's state, or "unknown" when the robot reported one that is not
    finite (RobotState.to_dict makes it None)."""
    return "unknown" if key in robot and robot[key] is None else robot.get(key)


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return "" if value is None else str(value)


def robot_status_json(robot: dict[str, Any]) -> str:
    """The robot state (RobotState.to_dict) as compact, strict JSON (a number that is not
    finite is null)."""
    return jsonout.dumps(robot, separators=(",", ":"), sort_keys=True)


def shorten(text: str, limit: int = 200) -> str:
    """Text for a status line: one line, at most `limit` characters."""
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[: limit - 3] + "..."
