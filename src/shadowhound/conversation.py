"""Answers to questions about the robot and its missions. Never moves the robot.

The agent hands a chat a `ChatContext` (what it may read, nothing it could move the robot
with: each service is typed by the few reading methods a chat uses); the offline answers and
the model's answers have one signature, `Chat`.
"""

from __future__ import annotations

import math
import re
import threading
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from .plan import PlanningError
from .planning import TRAVEL_QUESTION, Planner
from .skills.sense import describe_frame, travel_report

if TYPE_CHECKING:
    from .diagnostics import Progress
    from .llm.backend import LLMBackend
    from .planning import PlanningContext
    from .skills import Skill
    from .state import CameraFrame, RobotState


class RobotReadings(Protocol):
    """What a chat reads of the robot (`Robot`): its state, never a command."""

    def get_state(self) -> RobotState:
        """Raises RobotError when the robot cannot say."""
        ...


class CameraView(Protocol):
    """The latest camera frame (`crew.CameraFeed`)."""

    def latest(self) -> CameraFrame | None: ...


class ProgressReadings(Protocol):
    """The mission now and the last errors (`diagnostics.MissionTracker`)."""

    def snapshot(self) -> tuple[Progress, list[str]]: ...


class MissionRecords(Protocol):
    """The missions run (`logbook.Logbook`)."""

    def recent(self, limit: int) -> list[dict[str, Any]]:
        """Newest first."""
        ...


class Recall(Protocol):
    """Memories about a question (`memory.service.AgentMemory`)."""

    def search(self, query: str) -> list[str]: ...


class Briefing(Protocol):
    """What a planner, or a model's chat, may know (`crew.Crew`)."""

    def planning_context(
        self, text: str, planner: Planner | None, state: RobotState
    ) -> PlanningContext | None: ...


@dataclass(frozen=True, kw_only=True)
class ChatContext:
    """What a chat may read. Its services are read only when a question needs them."""

    robot: RobotReadings
    camera: CameraView
    tracker: ProgressReadings
    estop: bool
    skills: Iterable[Skill]  # the registry: missions people may say (Skill.example)
    missions: MissionRecords
    memory: Recall
    planner: Planner  # plans a question only to tell whether it is a mission
    briefing: Briefing

    def is_command(self, text: str) -> bool:
        """Would the planner plan this as a mission?"""
        try:
            self.planner.plan(text)
        except PlanningError:
            return False
        return True

    def planning(self, text: str) -> PlanningContext | None:
        """What a model may know, for a question (the robot's state read now)."""
        return self.briefing.planning_context(text, None, self.robot.get_state())


Chat = Callable[[str, ChatContext], str]

_TOPICS: list[tuple[str, re.Pattern[str]]] = [
    (
        "recall",
        re.compile(
            r"\b(did you see|have you seen|saw|remember|earlier|this morning|"
            r"yesterday|last time|where is|where are the)\b"
        ),
    ),
    ("see", re.compile(r"\b(see|seeing|look|view|camera|in front|ahead of you|surround)")),
    ("battery", re.compile(r"\b(battery|charge|charged|power|energy)\b")),
    ("where", re.compile(r"\b(where|position|pose|location|located|heading|facing)\b")),
    ("travel", TRAVEL_QUESTION),  # "how far have you walked?": the planner's words for it
    ("history", re.compile(r"\b(did|last|previous|recent|history|happened|missions?|done)\b")),
    ("skills", re.compile(r"\b(can you do|what can|skills?|abilities|help|commands?)\b")),
    ("status", re.compile(r"\b(status|how are you|state|posture|ok|okay|doing)\b")),
    ("greet", re.compile(r"^\s*(hi|hello|hey|good (morning|afternoon|evening))\b")),
]


def answer_offline(text: str, chat: ChatContext) -> str:
    """Pick the topics a question is about and answer each from what the chat context offers."""
    question = text.strip().lower()
    topics = [name for name, pattern in _TOPICS if pattern.search(question)]
    if "recall" in topics:  # a question about the past is not about the camera now
        topics = [t for t in topics if t not in ("see", "where")]
    if "travel" in topics:  # "how long have you been walking": not a question of missions
        topics = [t for t in topics if t not in ("history", "status")]
    if not topics or topics == ["status"] and chat.is_command(text):
        if chat.is_command(text):
            return (
                "That sounds like a mission. I only move when a mission is run: use "
                f'`shadowhound run "{text.strip()}"`, or type `/run {text.strip()}` in the '
                "chat."
            )
        return (
            "I can answer questions about where I am, my battery, what I see, what I did "
            "and what I can do. For anything else a language-model backend is needed."
        )
    st = chat.robot.get_state()
    answers = []
    for topic in dict.fromkeys(topics):
        if topic == "greet":
            answers.append("Hello! I am ShadowHound.")
        elif topic == "recall":
            found = chat.memory.search(text)
            answers.append(
                "I remember: " + " | ".join(found) if found else "I remember nothing about that."
            )
        elif topic == "see":
            answers.append(describe_frame(chat.camera.latest(), text))
        elif topic == "battery":
            answers.append(
                f"My battery is at {st.battery:.1f}%."
                if st.battery is not None
                else "I cannot tell my battery level: this robot reports none."
            )
        elif topic == "where":
            answers.append(
                f"I am at x={st.x:.2f} m, y={st.y:.2f} m, facing "
                f"{math.degrees(st.yaw):.0f} degrees (odom frame)."
            )
        elif topic == "travel":
            answers.append(travel_report(st) + ".")
        elif topic == "history":
            answers.append(_history(chat))
        elif topic == "skills":
            answers.append(_what_i_can_do(chat))
        elif topic == "status":
            progress, _errors = chat.tracker.snapshot()
            status = progress.status.value
            answers.append(
                f"I am {st.posture.value}, status {status}, battery "
                f"{st.battery_text}" + (", e-stop latched." if chat.estop else ".")
            )
    return " ".join(answers)


def _what_i_can_do(chat: ChatContext) -> str:
    """Missions said as a person says them (from the skills), and the questions answered."""
    examples = [e for skill in chat.skills if (e := skill.example()) is not None]
    said = "; ".join(f'"{example}"' for example in examples)
    return (
        f'Missions I understand, for example: {said}. Join them with "then" or commas; run '
        'one with `/run MISSION` in the chat or `shadowhound run "MISSION"`. I also answer '
        "questions: where are you? battery? what do you see? what did you do?"
    )


def _history(chat: ChatContext) -> str:
    recent = chat.missions.recent(3)  # from the history database when memory is enabled
    if not recent:
        return "I have not run any mission yet."
    lines = [f"{r['mission']!r}: {r['status']} ({r['response']})" for r in reversed(recent)]
    return f"My last {len(lines)} mission(s), oldest first: " + " | ".join(lines)


class ModelChat:
    """Answers in words from a language model (no tools: it cannot move). Keeps the last
    turns of the conversation so a follow-up question is understood."""

    def __init__(self, backend: LLMBackend, history_size: int) -> None:
        self.backend = backend
        self.history_size = history_size
        self._turns: deque[dict[str, str]] = deque(maxlen=2 * history_size)
        self._lock = threading.Lock()

    def __call__(self, text: str, chat: ChatContext) -> str:
        from .errors import BackendError
        from .planning import prompts

        ctx = chat.planning(text)
        lines = [
            "You are ShadowHound, a Unitree Go2 quadruped robot, answering your operator "
            "briefly. You cannot move in this conversation; missions are run separately."
        ]
        if ctx is not None:
            lines += [
                prompts.state_line(ctx.state),
                prompts.places_line(ctx.places),
                prompts.history_lines(ctx.history, self.history_size),
                prompts.memory_lines(ctx.memories),
            ]
        system = "\n".join(p for p in lines if p)
        with self._lock:
            turns = list(self._turns)
        try:
            completion = self.backend.complete(
                [{"role": "system", "content": system}, *turns, {"role": "user", "content": text}]
            )
        except BackendError as exc:
            return f"I cannot answer right now: {exc}"
        answer = str(completion.message.get("content") or "").strip() or "(no answer)"
        with self._lock:
            self._turns.extend(
                [{"role": "user", "content": text}, {"role": "assistant", "content": answer}]
            )
        return answer
