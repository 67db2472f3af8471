"""Perception and system skills: describe the view, look around, status, wait."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from pydantic import Field

from ..state import CameraFrame, RobotState
from ..units import format_number
from . import motion
from .arguments import Duration, NoArgs, SkillArgs
from .context import SkillContext
from .objects import sight_in_view
from .registry import Skill


class DescribeArgs(SkillArgs):
    question: str | None = Field(None, max_length=500, description="what to look for")


class WaitArgs(SkillArgs):
    seconds: Duration = Field(ge=0, le=3600, description="seconds to stand still")


def describe_frame(
    frame: CameraFrame | None,
    question: str | None,
    vision: Callable[[CameraFrame, str], str] | None = None,
) -> str:
    """Answer from the latest frame: with a vision model if one is configured, else honestly."""
    if frame is None:
        return "I have no camera image yet, so I cannot say what I see."
    if vision is not None:
        return vision(frame, question or "Describe what you see.")
    age = max(0.0, time.time() - frame.stamp)
    parts = [
        "No vision model is configured, so I cannot interpret the image myself. "
        f"I have a {frame.width}x{frame.height} {frame.encoding.upper()} frame from the "
        f"{frame.source}, {age:.1f} s old."
    ]
    if frame.sightings:
        seen = "; ".join(s.describe() for s in frame.sightings)
        parts.append(f"The simulator reports in view: {seen}.")
    elif frame.source == "simulator":
        parts.append("The simulator reports nothing in view but the room.")
    return " ".join(parts)


def _run_describe(ctx: SkillContext, a: DescribeArgs) -> str:
    sight_in_view(ctx)
    return describe_frame(ctx.camera_frame(), a.question, ctx.vision)


def _run_look_around(ctx: SkillContext, a: DescribeArgs) -> str:
    ctx.ensure_standing()
    views = []
    for quarter, side in enumerate(("ahead", "to my left", "behind me", "to my right")):
        if quarter:
            motion.rotate(ctx, math.pi / 2, ctx.config.motion.default_angular_speed)
        sight_in_view(ctx)  # what it sees is remembered (the world model, memory)
        views.append(f"{side}: {describe_frame(ctx.camera_frame(), a.question, ctx.vision)}")
    motion.rotate(ctx, math.pi / 2, ctx.config.motion.default_angular_speed)
    return " | ".join(views)


def _run_status(ctx: SkillContext, _a: NoArgs) -> str:
    st = ctx.robot.get_state()
    budget = ctx.env.budget
    return (
        f"{st.posture.value.capitalize()} at x={st.x:.2f} m, y={st.y:.2f} m, "
        f"facing {math.degrees(st.yaw):.0f} degrees; battery {st.battery_text}"
        + ("; e-stop latched" if st.estopped else "")
        + "; "
        + travel_report(st, budget.travelled(st) if budget is not None else None)
    )


def travel_report(state: RobotState, this_mission: float | None = None) -> str:
    """How far the robot has walked and turned, and for how long, from its odometer (since it
    started), and what the current mission has walked so far."""
    text = (
        f"I have walked {state.distance_travelled:.2f} m and turned "
        f"{math.degrees(state.angle_turned):.0f} degrees since I started, moving for "
        f"{_duration(state.time_moving)} in all (my odometer)"
    )
    if this_mission is not None:
        text += f"; {this_mission:.2f} m in this mission so far"
    return text


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, rest = divmod(round(seconds), 60)
    return f"{minutes} min {rest} s" if minutes < 60 else f"{minutes // 60} h {minutes % 60} min"


def _run_wait(ctx: SkillContext, a: WaitArgs) -> str:
    end = ctx.robot.now() + a.seconds
    while ctx.robot.now() < end - 1e-9:
        ctx.robot.sleep(min(ctx.period, end - ctx.robot.now()))
        ctx.check()
    return f"waited {a.seconds:g} s"


SKILLS = (
    Skill(
        "perception.describe",
        "Describe the camera's view, or answer a question about it. Does not move.",
        DescribeArgs,
        _run_describe,
        timeout=60.0,
        reports=True,
        remembered_as="observation",
        phrase=lambda a: "describe what I see",
    ),
    Skill(
        "perception.look_around",
        "Turn a full circle in place in quarter turns, describing each view.",
        DescribeArgs,
        _run_look_around,
        timeout=120.0,
        moves=True,
        predict=lambda p, a, env: [p],
        reports=True,
        phrase=lambda a: "look around",
    ),
    Skill(
        "sys.status",
        "Report pose, posture, battery and how far and long it has walked. Does not move.",
        NoArgs,
        _run_status,
        timeout=5.0,
        low_battery=True,
        reports=True,
        phrase=lambda a: "report status",
    ),
    Skill(
        "sys.wait",
        "Stand still for a number of seconds.",
        WaitArgs,
        _run_wait,
        timeout=lambda a, env: a.seconds + 5.0,
        waits=lambda a: a.seconds,
        phrase=lambda a: f"wait {format_number(a.seconds)} s",
    ),
)
