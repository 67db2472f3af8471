"""The dashboard shows what a step watches and what stopped it (issue 26), in real Chromium
against a real server and the simulated robot (whose default room has a red ball 2.4 m ahead
of the robot's start: something in the way)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from shadowhound.web import WebServer
from tests.web.conftest import make_agent
from tests.web.test_browser import DESKTOP, _playwright, launch, open_dashboard

Serve = Callable[..., WebServer]


def test_the_page_shows_the_watch_and_why_it_stopped(serve: Serve, tmp_path: Path) -> None:
    sync_playwright = _playwright()
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    errors: list[str] = []
    with sync_playwright() as p:
        browser = launch(p, tmp_path, DESKTOP)
        try:
            page = open_dashboard(browser, server.url, errors)
            page.fill("#command", "walk forward 2 meters unless something is in the way")
            page.click("#run")
            # While it walks: the step shows what it watches.
            watch = page.wait_for_selector("#steps li .watch")
            assert watch.text_content() == " unless something is in the way"
            page.wait_for_selector('#result[data-kind="error"]')
            step = page.locator("#steps li").nth(0)
            assert step.get_attribute("data-status") == "cancelled"
            note = step.locator(".note").text_content() or ""
            assert "stopped: red ball in the way" in note, note
            assert "(unless something is in the way)" in note
        finally:
            browser.close()
    truth = agent.robot.get_state()  # the simulator's own state: its truth
    assert 1.0 < truth.x < 2.0 - 0.3, truth  # it walked, and stopped short of the ball
    assert errors == []
