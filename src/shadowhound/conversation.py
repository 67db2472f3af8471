"""Offline answers to questions about the robot and its missions. Never moves the robot."""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING

from .plan import PlanningError
from .skills.sense import describe_frame

if TYPE_CHECKING:
    from .agent import RobotAgent

_TOPICS: list[tuple[str, re.Pattern[str]]] = [
    ("recall", re.compile(r"\b(did you see|have you seen|saw|remember|earlier|this morning|"
                          r"yesterday|last time|where is|where are the)\b")),
    ("see", re.compile(r"\b(see|seeing|look|view|camera|in front|ahead of you|surround)")),
    ("battery", re.compile(r"\b(battery|charge|charged|power|energy)\b")),
    ("where", re.compile(r"\b(where|position|pose|location|located|heading|facing)\b")),
    ("history", re.compile(r"\b(did|last|previous|recent|history|happened|missions?|done)\b")),
    ("skills", re.compile(r"\b(can you do|what can|skills?|abilities|help|commands?)\b")),
    ("status", re.compile(r"\b(status|how are you|state|posture|ok|okay|doing)\b")),
    ("greet", re.compile(r"^\s*(hi|hello|hey|good (morning|afternoon|evening))\b")),
]


def answer_offline(text: str, agent: RobotAgent) -> str:
    """Pick the topics a question is about and answer each from the agent's own records."""
    question = text.strip().lower()
    topics = [name for name, pattern in _TOPICS if pattern.search(question)]
    if "recall" in topics:  # a question about the past is not about the camera now
        topics = [t for t in topics if t not in ("see", "where")]
    if not topics or topics == ["status"] and _is_command(text, agent):
        if _is_command(text, agent):
            return ("That sounds like a mission. I only move when a mission is run: use "
                    f"`shadowhound run \"{text.strip()}\"`, or type `/run {text.strip()}` in the "
                    "chat.")
        return ("I can answer questions about where I am, my battery, what I see, what I did "
                "and what I can do. For anything else a language-model backend is needed.")
    st = agent.get_robot_state()
    answers = []
    for topic in dict.fromkeys(topics):
        if topic == "greet":
            answers.append("Hello! I am ShadowHound.")
        elif topic == "recall":
            found = agent.memory.search(text)
            answers.append("I remember: " + " | ".join(found) if found else
                           "I remember nothing about that.")
        elif topic == "see":
            answers.append(describe_frame(agent.latest_frame(), text))
        elif topic == "battery":
            answers.append(f"My battery is at {st.battery:.1f}%." if st.battery is not None
                           else "I cannot tell my battery level: this robot reports none.")
        elif topic == "where":
            answers.append(f"I am at x={st.x:.2f} m, y={st.y:.2f} m, facing "
                           f"{math.degrees(st.yaw):.0f} degrees (odom frame).")
        elif topic == "history":
            answers.append(_history(agent))
        elif topic == "skills":
            names = ", ".join(s["name"] for s in agent.get_available_skills())
            answers.append(f"My skills are: {names}.")
        elif topic == "status":
            diag = agent.get_diagnostics()
            answers.append(f"I am {st.posture.value}, status {diag['status']}, battery "
                           f"{st.battery_text}" + (", e-stop latched." if diag["estop"] else "."))
    return " ".join(answers)


def _is_command(text: str, agent: RobotAgent) -> bool:
    try:
        agent.planner.plan(text)
    except PlanningError:
        return False
    return True


def _history(agent: RobotAgent) -> str:
    recent = agent.recent_missions(3)  # from the history database when memory is enabled
    if not recent:
        return "I have not run any mission yet."
    lines = [f"{r['mission']!r}: {r['status']} ({r['response']})" for r in reversed(recent)]
    return f"My last {len(lines)} mission(s), oldest first: " + " | ".join(lines)
