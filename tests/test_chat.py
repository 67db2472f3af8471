"""`shadowhound chat` as a person uses it: a real process on a real terminal (a pty), typing a
line at a time and reading what the terminal shows; and through pipes, as a script does."""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import time

import pytest

from shadowhound import default_registry
from shadowhound.planning.rules import RulePlanner

PROMPT = "you> "
SAFETY = 120.0  # seconds: bounds a hung test (a loaded machine starts Python slowly)


class Terminal:
    """`shadowhound chat` on a pseudo-terminal: what a person types and sees."""

    def __init__(self, *args: str) -> None:
        self.master, slave = pty.openpty()
        env = {k: v for k, v in os.environ.items() if k != "SHADOWHOUND_CONFIG"}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "shadowhound", *args, "chat"],
            stdin=slave,
            stdout=slave,
            stderr=slave,
            env=env,
            close_fds=True,
        )
        os.close(slave)
        self.screen = ""

    def read_until(self, text: str, after: int = 0, timeout: float = SAFETY) -> str:
        """Everything shown from `after` until `text` appears after it; fails on timeout."""
        deadline = time.monotonic() + timeout
        while text not in self.screen[after:]:
            left = deadline - time.monotonic()
            assert left > 0, f"no {text!r} on the terminal after {timeout} s:\n{self.screen}"
            ready, _, _ = select.select([self.master], [], [], left)
            if ready:
                try:
                    chunk = os.read(self.master, 4096).decode(errors="replace")
                except OSError:  # the process ended
                    chunk = ""
                assert chunk, f"the chat ended before {text!r}:\n{self.screen}"
                self.screen += chunk.replace("\r\n", "\n")
        return self.screen[after : self.screen.index(text, after) + len(text)]

    def ask(self, line: str) -> str:
        """Type `line` at the prompt; what the terminal shows until the next prompt."""
        start = len(self.screen)
        os.write(self.master, (line + "\n").encode())
        shown = self.read_until(line + "\n", start)  # the terminal's echo of the typing
        return self.read_until(PROMPT, start + len(shown))[: -len(PROMPT)]

    def close(self) -> int:
        os.write(self.master, b"/quit\n")
        code = self.proc.wait(SAFETY)
        os.close(self.master)
        return code


@pytest.fixture
def terminal():
    term = Terminal()
    term.read_until(PROMPT)
    yield term
    assert term.close() == 0


def test_each_answer_comes_before_the_next_prompt(terminal):
    for question, answer in [
        ("where are you?", "I am at x=0.00 m, y=0.00 m"),
        ("battery?", "My battery is at 100.0%"),
        ("/help", "/run MISSION"),
    ]:
        shown = terminal.ask(question)
        assert answer in shown, terminal.screen  # shown before the next "you> "
    assert terminal.screen.count(PROMPT) == 4  # one per line typed, and the first


def test_status_is_in_words(terminal):
    shown = terminal.ask("/status")
    assert "{" not in shown and '"x"' not in shown, shown
    assert "standing at x=0.00 m, y=0.00 m, facing 0 degrees" in shown.lower(), shown
    assert "battery 100.0%" in shown and "e-stop released" in shown.lower(), shown


def test_run_shows_each_step_as_it_starts_and_ends(terminal):
    shown = terminal.ask("/run stand up, walk forward 1 meter and turn left 90 degrees")
    lines = [line.strip() for line in shown.strip().splitlines()]
    steps = [line for line in lines if line.startswith("[")]
    assert steps[0] == "[1] body.stand() ..."
    assert steps[2] == "[2] nav.move(distance=1.0) ..."
    assert steps[3].startswith("[2] ok: moved 1.00 m forward")
    assert steps[5].startswith("[3] ok: turned 90.0 degrees left")
    assert lines[-1].startswith("ok: Done: ")  # the answer after its steps
    assert lines.index(steps[-1]) < len(lines) - 1


def test_a_step_is_shown_while_the_mission_walks():
    """In real time: the step shows up on the terminal while its walk is under way, not with the
    mission's answer: a /stop typed once the step is shown still finds the mission running
    (and stops it short). The walk is slow (20 s), so the /stop lands during it on any
    machine."""
    term = Terminal("--time-scale", "1")
    try:
        term.read_until(PROMPT)
        start = len(term.screen)
        os.write(term.master, b"/run walk forward 2 meters at 0.1 m/s\n")
        term.read_until("nav.move(distance=2.0, speed=0.1) ...", start)
        assert "ok: Done" not in term.screen[start:]
        os.write(term.master, b"/stop\n")
        term.read_until("stopping 'walk forward 2 meters at 0.1 m/s'", start)
        term.read_until("failed: Stopped at step 1 (nav.move): mission cancelled", start)
        assert "ok: Done" not in term.screen[start:]
    finally:
        assert term.close() == 0


def test_what_can_you_do_answers_with_sentences(terminal):
    shown = terminal.ask("what can you do?")
    assert not re.search(r"\b(nav|body|sys|perception)\.[a-z_]+", shown), shown
    for sentence in ('"turn left 90 degrees"', '"move forward 1 m"', '"sit down"'):
        assert sentence in shown, shown
    assert "where are you?" in shown


def test_every_example_is_a_sentence_the_offline_planner_plans_into_its_skill():
    planner = RulePlanner()
    examples = {s.name: s.example() for s in default_registry()}
    offered = {name: text for name, text in examples.items() if text}
    assert len(offered) >= 12, examples
    for name, text in offered.items():
        assert [step.skill for step in planner.plan(text).steps] == [name], text


def test_estop_still_acts_at_once_on_the_terminal():
    term = Terminal("--time-scale", "1")
    try:
        term.read_until(PROMPT)
        start = len(term.screen)
        os.write(term.master, b"/run walk backward 2 meters at 0.1 m/s\n")  # 20 s: /estop lands
        term.read_until("nav.move(distance=-2.0, speed=0.1) ...", start)
        asked = len(term.screen)
        os.write(term.master, b"/estop\n")
        # Both, in either order: the answer to /estop and the mission's end it caused (the
        # mission's thread and the prompt's print race on a loaded machine; neither waits).
        term.read_until("e-stop latched", asked)
        term.read_until("failed: Stopped at step 1 (nav.move): e-stop pressed.", asked)
    finally:
        assert term.close() == 0


def test_through_pipes_the_steps_go_to_stderr_before_the_answer():
    proc = subprocess.run(
        [sys.executable, "-m", "shadowhound", "chat"],
        input="/run walk forward 1 meter\n/status\n",
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=SAFETY,
        env={k: v for k, v in os.environ.items() if k != "SHADOWHOUND_CONFIG"},
    )
    assert proc.returncode == 0
    lines = proc.stdout.splitlines()
    assert PROMPT not in proc.stdout  # no terminal: no prompts
    walked = next(i for i, line in enumerate(lines) if line.startswith("ok: Done: moved 1.00 m"))
    assert any("[1] ok: moved 1.00 m forward" in line for line in lines[:walked]), lines
    assert lines[walked + 1].lower().startswith("standing at x=1.00 m"), lines
