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


Vision = Callable[[CameraFrame, str], str]


def describe_frame(
    frame: CameraFrame | None, question: str | None, vision: Vision | None = None
) -> str:
    """Answer from the latest frame: with a vision model if one is configured; without one,
    what is known to be in view first, then once what a vision model would add."""
    if frame is None:
        return NO_IMAGE
    if vision is not None:
        return vision(frame, question or "Describe what you see.")
    seen = _known_in_view(frame)
    if not seen:
        return _without_vision([frame])
    return f"{'In view: ' if frame.sightings else ''}{seen} {_without_vision([frame])}"


def describe_views(
    views: list[tuple[str, CameraFrame | None]], question: str | None, vision: Vision | None
) -> str:
    """One line per view ("Ahead: ..."), then, without a vision model, one line saying what a
    vision model would add (said once, not once a view)."""
    frames = [frame for _, frame in views if frame is not None]
    if not frames:
        return NO_IMAGE
    lines = []
    for side, frame in views:
        if frame is None:
            said = "no image"
        elif vision is not None:
            said = vision(frame, question or "Describe what you see.")
        else:
            said = _known_in_view(frame) or "nothing I can name."
        lines.append(f"{side}: {said}")
    if vision is None:
        lines.append(_without_vision(frames))
    return "\n".join(lines)


NO_IMAGE = "I have no camera image yet, so I cannot say what I see."


def _known_in_view(frame: CameraFrame) -> str:
    """What the robot knows is in the frame's view ("" when it knows nothing of it)."""
    if frame.sightings:
        return "; ".join(s.describe() for s in frame.sightings) + "."
    if frame.source == "simulator":
        return "Nothing in view but the room."
    return ""


def _without_vision(frames: list[CameraFrame]) -> str:
    """What the answer lacks without a vision model, and the frames it had, said briefly."""
    first = frames[0]
    kind = f"{first.width}x{first.height} {first.encoding.upper()}"
    if first.source == "simulator":
        what = "images themselves" if len(frames) > 1 else "image itself"
        frames_of = f"{kind} frames" if len(frames) > 1 else f"a {kind} frame"
        return (
            f"A vision model (llm.vision) would describe the {what}; this is the simulator's "
            f"list of what is in view ({frames_of})."
        )
    age = max(0.0, time.time() - first.stamp)
    return (
        f"I have a {kind} frame from the {first.source}, {age:.1f} s old, but no vision model "
        "to look at it; one (llm.vision) would describe what it shows."
    )


def _run_describe(ctx: SkillContext, a: DescribeArgs) -> str:
    sight_in_view(ctx)
    return describe_frame(ctx.camera_frame(), a.question, ctx.vision)


def _run_look_around(ctx: SkillContext, a: DescribeArgs) -> str:
    ctx.ensure_standing()
    views: list[tuple[str, CameraFrame | None]] = []
    for quarter, side in enumerate(("Ahead", "To my left", "Behind me", "To my right")):
        if quarter:
            motion.rotate(ctx, math.pi / 2, ctx.config.motion.default_angular_speed, relative=True)
        sight_in_view(ctx)  # what it sees is remembered (the world model, memory)
        views.append((side, ctx.camera_frame()))
    motion.rotate(ctx, math.pi / 2, ctx.config.motion.default_angular_speed, relative=True)
    return describe_views(views, a.question, ctx.vision)


def _run_status(ctx: SkillContext, _a: NoArgs) -> str:
    st = ctx.robot.get_state()
    budget = ctx.env.budget
    mission = budget.travelled(st) if budget is not None else None
    return (
        st.in_words()
        + ("; e-stop latched" if st.estopped else "")
        + f"; turned {math.degrees(st.angle_turned):.0f} degrees and moving for "
        + f"{_duration(st.time_moving)} since it started (its odometer)"
        + (f"; {mission:.2f} m in this mission so far" if mission is not None else "")
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
        "Turn a full circle in quarter turns, describing each view.",
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
