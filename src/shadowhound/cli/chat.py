"""`shadowhound chat`: a REPL over the agent's chat and the mission worker.

Questions are answered by `RobotAgent.chat` (never moving the robot); `/run MISSION` runs one on
the worker and shows its steps as `run` does; `/estop` and `/stop` (or a plain "stop") act at
once, whatever is in flight.
"""

from __future__ import annotations

import argparse
import queue
import sys
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .. import events as ev
from ..config import ShadowHoundConfig
from ..exit_codes import EXIT_OK
from ..result import MissionStatus
from ..worker import MissionJob, MissionWorker
from ._base import make_agent
from .missions import progress

if TYPE_CHECKING:
    from ..diagnostics import Diagnostics

_CHAT_HELP = (
    "Ask a question (where are you? battery? what do you see? what did you do?), or: "
    "/run MISSION, /stop (or just 'stop'), /status, /skills, /estop, /release, /help, /quit"
)


def cmd_chat(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    agent = make_agent(settings)
    worker = MissionWorker(agent)
    screen = _ChatScreen(prompting=sys.stdin.isatty())
    agent.add_listener(screen.locked(progress(sys.stderr, agent.registry)))
    if screen.prompting:
        print("ShadowHound chat. " + _CHAT_HELP)
    # Missions and questions are answered in order on another thread, so this one keeps reading:
    # a /estop typed while a mission walks or a model thinks acts at once.
    lines: queue.Queue[str | None] = queue.Queue()
    answered = threading.Event()

    def answer() -> None:
        try:
            while (line := lines.get()) is not None:
                screen.answer(_chat_line(agent, worker, line))
        finally:
            answered.set()

    threading.Thread(target=answer, name="shadowhound-chat", daemon=True).start()
    try:
        screen.prompt_when_idle()
        while True:
            line = sys.stdin.readline()
            if not line:
                break
            line = line.strip()
            if line in ("/quit", "/exit"):
                break
            if not line:
                screen.prompt_when_idle()
            elif line.split()[0] in ("/estop", "/stop") or _says_stop(line):
                screen.say_now(_chat_line(agent, worker, line))  # at once, out of turn
            else:
                screen.waiting()
                lines.put(line)
        lines.put(None)
        while not answered.wait(0.1):  # an Event, not join: Ctrl-C here must still stop
            pass
        if screen.gone:
            raise BrokenPipeError("the chat's output was closed")  # main() ends quietly
    except KeyboardInterrupt:
        worker.estop()
    finally:
        worker.stop(timeout=0.0)  # the mission (if any) was stopped; do not wait for it
        agent.cleanup()
    return EXIT_OK


class _ChatScreen:
    """What the chat shows, from two threads: answers (stdout), a mission's steps (stderr, as
    `run` shows them) and, on a terminal, the prompt. Each is shown whole, and the prompt only
    once every line typed so far is answered, so an answer never lands after a new prompt."""

    def __init__(self, prompting: bool) -> None:
        self.prompting = prompting
        self.gone = False  # stdout was closed (a pipe whose reader went away)
        self._lock = threading.Lock()
        self._unanswered = 0

    def waiting(self) -> None:
        """A line was handed to the answering thread."""
        with self._lock:
            self._unanswered += 1

    def answer(self, text: str) -> None:
        """The answer to the oldest line waiting."""
        with self._lock:
            self._unanswered -= 1
            self._show(text)

    def say_now(self, text: str) -> None:
        """An answer out of turn (/estop)."""
        with self._lock:
            self._show(text)

    def prompt_when_idle(self) -> None:
        with self._lock:
            self._show(None)

    def locked(self, listener: ev.Listener) -> ev.Listener:
        def show(event: ev.MissionEvent) -> None:
            with self._lock:
                listener(event)

        return show

    def _show(self, text: str | None) -> None:
        if self.gone:
            return
        try:
            if text is not None:
                print(text, flush=True)
            if self.prompting and not self._unanswered:
                print("you> ", end="", flush=True)
        except BrokenPipeError:  # whoever read the chat went away: nothing more is shown
            self.gone = True


def _chat_line(agent: Any, worker: MissionWorker, line: str) -> str:
    if line.startswith("/run"):
        mission = line[4:].strip()
        if not mission:
            return "usage: /run MISSION"
        job = MissionJob(mission, source="cli")
        refused = worker.submit(job)
        if refused is not None:
            return "refused: " + refused
        job.done.wait()  # answers come in order: the next line waits for this mission
        if job.result is None:
            return f"failed: {job.dropped}"
        return ("ok: " if job.result.success else "failed: ") + job.result.response
    commands: dict[str, Callable[[], str]] = {
        "/status": lambda: _status(agent.diagnostics()),
        "/skills": lambda: ", ".join(s["name"] for s in agent.get_available_skills()),
        "/estop": lambda: (worker.estop(), "e-stop latched; /release to release it")[1],
        "/stop": lambda: _stop(worker),
        "/release": lambda: (agent.release_estop(), "e-stop released")[1],
        "/help": lambda: _CHAT_HELP,
    }
    if _says_stop(line):
        return _stop(worker)
    if line.startswith("/"):
        action = commands.get(line.split()[0])
        return action() if action else f"unknown command {line.split()[0]!r}. {_CHAT_HELP}"
    return str(agent.chat(line))


def _says_stop(line: str) -> bool:
    """A person's stop ("stop", "No, stop!", "that's enough": what push-to-talk takes for a
    stop, hearing.is_stop): the running mission's stop, answered at once (a mission "until I
    say stop" then ends as asked)."""
    from ..hearing import is_stop

    return not line.startswith("/") and is_stop(line)


def _stop(worker: MissionWorker) -> str:
    """/stop: cancel the running mission; the robot stops."""
    job = worker.current
    if job is None:
        return "no mission is running"
    worker.cancel(job.mission_id)
    return f"stopping {job.command!r}"


def _status(now: Diagnostics) -> str:
    """/status: the robot, the e-stop and the mission, in words."""
    robot = now.robot.in_words() if now.robot else f"I cannot read the robot: {now.robot_error}"
    estop = "e-stop latched (/release releases it)" if now.estop else "e-stop released"
    p = now.progress
    if p.status in (MissionStatus.PLANNING, MissionStatus.EXECUTING):
        step = f", step {p.step} of {p.steps} ({p.skill})" if p.steps and p.skill else ""
        mission = f"{p.status.value} {p.mission!r}{step}"
    else:
        mission = "no mission running"
    return f"{robot}. {estop[0].upper()}{estop[1:]}; {mission}."
