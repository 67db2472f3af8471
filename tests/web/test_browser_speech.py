"""Push-to-talk in a real browser (issue 27): headless Chromium whose fake microphone plays a
WAV spoken by espeak-ng, the dashboard on a real server, a scripted OpenAI-compatible
transcription server; judged by the simulated robot's state and what the server received."""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from shadowhound.hearing import inspect
from shadowhound.web import WebServer
from tests.speech_server import ScriptedTranscriber
from tests.web.conftest import make_agent, wait_for
from tests.web.test_browser import ARTIFACTS, DESKTOP, PHONE, _playwright, launch, open_dashboard


@pytest.fixture(scope="module")
def spoken(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ "walk forward one meter", spoken by espeak-ng into a WAV."""
    if not shutil.which("espeak-ng"):
        message = "the push-to-talk test needs espeak-ng (apt-get install espeak-ng)"
        if os.environ.get("CI"):
            pytest.fail(message + " (CI is set, so this must not be skipped)")
        pytest.skip(message)
    path = tmp_path_factory.mktemp("speech") / "walk.wav"
    subprocess.run(["espeak-ng", "-w", str(path), "walk forward one meter"], check=True)
    return path


def browser(p: Any, tmp_path: Path, wav: Path, viewport: dict[str, int] = DESKTOP) -> Any:
    """Chromium whose microphone plays `wav` (and which asks nobody for it)."""
    return launch(
        p,
        tmp_path,
        viewport,
        "--use-fake-ui-for-media-stream",
        "--use-fake-device-for-media-stream",
        f"--use-file-for-fake-audio-capture={wav}",
    )


# What the page reads aloud, kept instead of spoken (headless Chromium has no voices).
SPOKEN = """
window.__spoken = [];
if ("speechSynthesis" in window) {
  window.speechSynthesis.speak = (utterance) => { window.__spoken.push(utterance.text); };
}
"""


def open_page(context: Any, server: WebServer, errors: list[str]) -> Any:
    return open_dashboard(context, server.url, errors, init_script=SPOKEN)


def press(page: Any) -> None:
    box = page.locator("#talk").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.wait_for_selector('#talk[data-state="recording"]')


def hold(page: Any, seconds: float) -> None:
    """Keep holding until the page has recorded `seconds` of sound."""
    page.wait_for_function(
        f"() => Number(document.querySelector('#talk').dataset.recorded || 0) >= {seconds}"
    )


def release(page: Any) -> None:
    page.mouse.up()


def test_holding_the_button_runs_what_was_said(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber, spoken: Path, tmp_path: Path
) -> None:
    sync_playwright = _playwright()
    agent = make_agent(time_scale=0.5, speech={"base_url": heard.url})
    server = serve(agent)
    heard.script("Walk forward one meter.")
    errors: list[str] = []
    with sync_playwright() as p:
        context = browser(p, tmp_path, spoken)
        try:
            page = open_page(context, server, errors)
            page.wait_for_selector('#talk[data-configured="true"]')
            page.check("#speak-answers")
            press(page)
            hold(page, 1.5)  # while the fake microphone plays the sentence
            release(page)
            page.wait_for_selector('#heard:has-text("Walk forward one meter.")')
            page.wait_for_selector('#result[data-kind="ok"]')
            assert page.input_value("#command") == "Walk forward one meter."
            # The result was read aloud, once (the person turned that on).
            assert page.evaluate("window.__spoken") == ["Done: moved 1.00 m forward."]
            page.screenshot(path=str(ARTIFACTS / "dashboard-talk.png"), full_page=True)
        finally:
            context.close()
    assert not errors, errors
    assert agent.robot.get_state().x == pytest.approx(1.0, abs=0.02)  # the simulator's truth
    [request] = heard.requests
    # What Chromium's MediaRecorder made is what reached the transcription server, and its
    # container says how long the person held the button.
    assert request.file_type in ("audio/webm", "audio/ogg"), request.file_type
    assert 1.2 < inspect(request.file, request.file_type).seconds < 10.0
    assert request.fields["model"] == "whisper-1"


def test_a_spoken_stop_during_a_walk_latches_the_estop(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber, spoken: Path, tmp_path: Path
) -> None:
    sync_playwright = _playwright()
    agent = make_agent(time_scale=1.0, speech={"base_url": heard.url})
    server = serve(agent)
    heard.script("walk backward 3 meters", "stop")
    errors: list[str] = []
    with sync_playwright() as p:
        context = browser(p, tmp_path, spoken)
        try:
            page = open_page(context, server, errors)
            page.wait_for_selector('#talk[data-configured="true"]')
            press(page)
            hold(page, 0.5)
            release(page)
            wait_for(lambda: agent.robot.get_state().vx < -0.1, 15, "the walk")
            press(page)
            hold(page, 0.5)
            release(page)
            page.wait_for_selector("#estop-banner:not([hidden])")
            page.wait_for_selector('#heard:has-text("stop")')
        finally:
            context.close()
    assert agent.estop_latched
    state = agent.robot.get_state()
    assert state.vx == 0.0 and -3.0 < state.x < -0.05  # stopped on the way, in truth
    assert len(heard.requests) == 2


def test_a_recording_longer_than_allowed_is_dropped_with_a_message(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber, spoken: Path, tmp_path: Path
) -> None:
    sync_playwright = _playwright()
    agent = make_agent(speech={"base_url": heard.url, "max_seconds": 1.0})
    server = serve(agent)
    errors: list[str] = []
    with sync_playwright() as p:
        context = browser(p, tmp_path, spoken)
        try:
            page = open_page(context, server, errors)
            page.wait_for_selector('#talk[data-configured="true"]')
            press(page)
            page.wait_for_selector('#talk-msg:has-text("longer than 1 s")')  # still held
            release(page)
            assert page.get_attribute("#talk", "data-state") == "idle"
        finally:
            context.close()
    assert not errors, errors
    assert heard.requests == [] and agent.history == []


def test_without_a_server_the_button_says_how_to_set_one_up_and_stop_is_always_on_screen(
    serve: Callable[..., WebServer], spoken: Path, tmp_path: Path
) -> None:
    sync_playwright = _playwright()
    server = serve(make_agent())
    errors: list[str] = []
    with sync_playwright() as p:
        for name, viewport in (("desktop", DESKTOP), ("phone", PHONE)):
            context = browser(p, tmp_path / name, spoken, viewport)
            try:
                page = open_page(context, server, errors)
                page.wait_for_selector('#talk[data-configured="false"]')
                page.click("#talk")
                page.wait_for_selector('#talk-msg:has-text("speech.base_url")')
                for selector in ("#estop", "#talk"):
                    box = page.locator(selector).bounding_box()
                    assert box and box["x"] >= 0 and box["y"] >= 0, (name, selector)
                    assert box["x"] + box["width"] <= viewport["width"], (name, selector, box)
                    assert box["height"] >= 40, (name, selector, box)  # a touch target
                page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
                box = page.locator("#estop").bounding_box()  # the header stays on screen
                assert box and 0 <= box["y"] < viewport["height"], (name, box)
                page.screenshot(path=str(ARTIFACTS / f"dashboard-{name}.png"))
            finally:
                context.close()
    assert not errors, errors
