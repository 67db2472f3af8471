"""What the robot says reaches the dashboard: a `spoken` event on the live feed of a real
server, and a line under the mission's steps in a real browser (spoken by the browser too
when the person turns that on)."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest

from shadowhound.web import WebServer
from tests.web.conftest import SAFETY, TOKEN, make_agent
from tests.web.test_browser import ARGS, CHROMIUM, PHONE, _playwright

websockets_sync = pytest.importorskip(
    "websockets.sync.client", reason="the websockets package is needed"
)

Serve = Callable[..., WebServer]


def _until(ws: Any, kind: str, timeout: float = SAFETY) -> list[dict[str, Any]]:
    seen: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        message = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        if message["kind"] != "state":
            seen.append(message)
        if message["kind"] == kind:
            return seen
    raise AssertionError(f"no {kind!r} within {timeout} s; saw {[m['kind'] for m in seen]}")


def test_the_words_reach_the_live_feed_while_their_step_runs(serve: Serve) -> None:
    server = serve(make_agent(), token=TOKEN)
    url = server.url.replace("http://", "ws://") + "/ws/status"
    with websockets_sync.connect(url, subprotocols=["shadowhound", f"bearer.{TOKEN}"]) as ws:
        assert json.loads(ws.recv(timeout=SAFETY))["kind"] == "snapshot"
        reply = httpx.post(
            server.url + "/api/mission",
            json={"command": "say good morning, then say it is nice to see you"},
            headers={"Authorization": f"Bearer {TOKEN}"},
            timeout=SAFETY,
        )
        events = _until(ws, "mission_record")
    mission_id = reply.json()["mission_id"]
    spoken = [e for e in events if e["kind"] == "spoken"]
    assert [(e["text"], e["aloud"], e["step"]) for e in spoken] == [
        ("Good morning!", True, 1),
        ("It is nice to see you", True, 3),
    ]
    assert all(e["mission_id"] == mission_id and e["why_silent"] == "" for e in spoken)
    kinds = [
        (e["kind"], e.get("step", {}).get("index") if e["kind"] != "spoken" else e["step"])
        for e in events
        if e["kind"] in ("step_started", "step_finished", "spoken")
    ]
    first = kinds.index(("spoken", 1))
    assert kinds[first - 1] == ("step_started", 1) and kinds[first + 1] == ("step_finished", 1)


def test_the_page_shows_what_the_robot_said_and_can_speak_it(serve: Serve, tmp_path: Path) -> None:
    sync_playwright = _playwright()
    server = serve(make_agent(time_scale=0.5, safety={"max_speech_per_minute": 1}))
    errors: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch_persistent_context(
            str(tmp_path / "profile"),
            executable_path=CHROMIUM,
            headless=True,
            args=ARGS,
            viewport=PHONE,
        )
        try:
            page = browser.new_page()
            # The browser's own voice, recorded: what the page asks it to say.
            page.add_init_script(
                "window.__said = [];"
                "Object.defineProperty(window, 'speechSynthesis', {configurable: true,"
                " value: {speak: (u) => window.__said.push(u.text)}});"
            )
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.set_default_timeout(SAFETY * 1000)
            page.goto(server.url + "/", wait_until="domcontentloaded")
            page.wait_for_selector('#conn[data-state="live"]')
            page.check("#voice-here")
            page.fill("#command", "say hello then say good bye")
            page.click("#run")
            page.wait_for_selector('#result[data-kind="ok"]')
            lines = page.locator("#spoken li")
            assert lines.count() == 2
            assert lines.nth(0).text_content() == "said: \u201cHello!\u201d"
            assert lines.nth(0).get_attribute("data-aloud") == "true"
            # Over the rate (one a minute here): shown, with why, and not spoken.
            second = lines.nth(1).text_content() or ""
            assert second.startswith(
                "not said aloud (over the rate: it may say 1 a minute"
            ) and second.endswith("\u201cGood bye!\u201d"), second
            assert page.evaluate("window.__said") == ["Hello!"]
            # A new mission starts with no words under it.
            page.fill("#command", "sit down")
            page.click("#run")
            # Waited on the new mission itself: the last one's steps are still on the page (and
            # succeeded) until the new one starts, so waiting on them raced the new mission.
            page.wait_for_selector('#current-text:has-text("sit down")')
            page.wait_for_selector('#result[data-kind="ok"]')
            assert page.locator("#spoken li").count() == 0
        finally:
            browser.close()
    assert errors == []
