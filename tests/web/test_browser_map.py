"""The dashboard's map in a real browser (headless Chromium via Playwright, as test_browser.py):
the occupancy grid, the known objects, a dry run's planned path and a mission's walked path are
drawn where they are. The canvas's own bitmap is read back with the transform the page left on
it (centre and pixels per metre), so the test knows where each thing must be."""

from __future__ import annotations

import contextlib
import io
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shadowhound.web import WebServer
from tests.web.conftest import SAFETY, make_agent, wait_for
from tests.web.test_browser import ARTIFACTS, _playwright, launch

DESKTOP = {"width": 1100, "height": 900}
OBJECT = (195, 107, 29)  # the object fill (230, 126, 34, 85 %) over an occupied (black) cell
PLANNED = (63, 111, 181)
WALKED = (47, 125, 50)


class Canvas:
    """The map canvas's own pixels and the transform it was drawn with (metres -> pixels).

    Both are read in one step of the page (its bitmap as a PNG and the data-cx/cy/scale it left
    on the canvas), so neither a redraw nor the page's layout moving can come between them: a
    screenshot of the element was cut from where the canvas had been a moment before, 4 px off
    once a message above it changed height (CI saw the walked line "missing")."""

    def __init__(self, page: Any) -> None:
        import base64

        from PIL import Image

        drawn = page.evaluate(
            """() => {
                const c = document.querySelector("#map");
                return {png: c.toDataURL("image/png"), cx: c.dataset.cx, cy: c.dataset.cy,
                        scale: c.dataset.scale, width: c.width, height: c.height};
            }"""
        )
        png = base64.b64decode(drawn["png"].split(",", 1)[1])
        self.image = Image.open(io.BytesIO(png)).convert("RGB")
        self.cx, self.cy, self.scale = (float(drawn[k] or "nan") for k in ("cx", "cy", "scale"))
        self.ratio = self.image.width / drawn["width"]
        self.half = (drawn["width"] / 2, drawn["height"] / 2)

    def at(self, x: float, y: float) -> tuple[int, int, int]:
        px = (self.half[0] + (x - self.cx) * self.scale) * self.ratio
        py = (self.half[1] - (y - self.cy) * self.scale) * self.ratio
        value: tuple[int, int, int] = self.image.getpixel((round(px), round(py)))
        return value

    def around(self, x: float, y: float, pixels: int = 3) -> list[tuple[int, int, int]]:
        """The pixels within a few of (x, y): a 10 cm wall is 3 px wide, antialiased."""
        px = (self.half[0] + (x - self.cx) * self.scale) * self.ratio
        py = (self.half[1] - (y - self.cy) * self.scale) * self.ratio
        return [
            self.image.getpixel((round(px) + i, round(py) + j))
            for i in range(-pixels, pixels + 1)
            for j in range(-pixels, pixels + 1)
        ]

    def along(
        self, points: list[tuple[float, float]], colour: tuple[int, int, int], within: float = 0.0
    ) -> float:
        """The share of points sampled every 2 cm along the polyline with `colour` drawn at
        them (or, given `within` metres, somewhere that close: a walked path is where the body
        went, a few centimetres off the planned one, and is drawn 2 px wide)."""
        steps = [i * 0.02 for i in range(-int(within / 0.02), int(within / 0.02) + 1)]
        # Every 2 cm along the legs (not the last point: the robot's marker is drawn there).
        points = sampled(points)[1:]
        hits = sum(
            any(near(self.at(x + dx, y + dy), colour) for dx in steps for dy in steps)
            for x, y in points
        )
        return hits / max(1, len(points))


def keep(frames: list[dict[str, Any]], payload: str | bytes) -> None:
    """The live feed's messages as the page received them."""
    with contextlib.suppress(ValueError):
        message = json.loads(payload)
        if isinstance(message, dict):
            frames.append(message)


def trail_sent(frames: list[dict[str, Any]]) -> list[tuple[float, float]]:
    """The walked path the page draws: where the robot was when the mission's plan arrived,
    then every pose of a state message after it (as app.js keeps them, 1 cm apart)."""
    trail: list[tuple[float, float]] = []
    for message in frames:
        if message.get("kind") == "plan_ready":
            trail = trail[-1:]
        if message.get("kind") not in ("state", "snapshot"):
            continue
        robot = (message["status"] if message["kind"] == "snapshot" else message).get("robot")
        if isinstance(robot, dict) and "x" in robot:
            point = (float(robot["x"]), float(robot["y"]))
            if not trail or math.dist(point, trail[-1]) > 0.01:
                trail.append(point)
    return trail


def sampled(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points every 2 cm along a polyline."""
    out = points[-1:]
    for (x0, y0), (x1, y1) in zip(points, points[1:], strict=False):
        n = max(1, int(math.dist((x0, y0), (x1, y1)) / 0.02))
        out += [(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n) for i in range(n)]
    return out


def near(rgb: tuple[int, int, int], colour: tuple[int, int, int], tolerance: int = 30) -> bool:
    return all(abs(a - b) <= tolerance for a, b in zip(rgb, colour, strict=True))


def test_the_map_draws_grid_objects_planned_and_walked_paths(
    serve: Callable[..., WebServer], tmp_path: Path
) -> None:
    sync_playwright = _playwright()
    # Real time: the walk back in part 4 takes seconds, so STOP lands before the ball on any
    # machine (at four times as fast it raced the click on a loaded one).
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    ARTIFACTS.mkdir(exist_ok=True)
    planned = [(p.x, p.y) for p in agent.dry_run("go to x=4, y=0").predicted_path]
    assert max(abs(y) for _, y in planned) > 0.3  # around the red ball at (3, 0)
    # Planning looked: the ball and the box are in view. The dock behind the robot is known
    # as a detector would report it (one call for every source of sightings).
    belief = agent.robot.belief()
    assert belief is not None and {o.name for o in belief.objects} >= {"red ball", "blue box"}
    belief.sight("charging dock", -3.0, -1.0, stamp=agent.robot.now())
    errors: list[str] = []
    with sync_playwright() as p:
        browser = launch(p, tmp_path, DESKTOP)
        try:
            page = browser.new_page()
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.set_default_timeout(SAFETY * 1000)
            grids: list[str] = []
            page.on("request", lambda r: grids.append(r.url) if "grid.png" in r.url else None)
            frames: list[dict[str, Any]] = []
            page.on("websocket", lambda ws: ws.on("framereceived", lambda f: keep(frames, f)))
            page.goto(server.url + "/", wait_until="domcontentloaded")
            page.wait_for_selector('#conn[data-state="live"]')
            page.wait_for_selector('#map[data-grid]:not([data-grid=""])')
            page.wait_for_selector('#map-objects li[data-name="red ball"]')
            assert "3.0, 0.0 m" in page.text_content('#map-objects li[data-name="red ball"]')

            # 1. The grid and the objects, where they are.
            canvas = Canvas(page)
            assert near(canvas.at(0.5, 1.5), (254, 254, 254), 12)  # free floor
            assert any(near(rgb, (0, 0, 0), 40) for rgb in canvas.around(-6.05, 0.5))  # wall
            assert not any(near(rgb, (0, 0, 0), 40) for rgb in canvas.around(-5.5, 0.5))
            for x, y in ((3.0, 0.0), (2.5, 2.0), (-3.0, -1.0)):  # ball, box, dock
                assert near(canvas.at(x, y), OBJECT), (x, y, canvas.at(x, y))

            # 2. A dry run's planned path, around the ball.
            page.fill("#command", "go to x=4, y=0")
            page.click("#dry-run")
            page.wait_for_selector('#result[data-kind="ok"]')
            canvas = Canvas(page)
            assert canvas.along(planned, PLANNED) > 0.3  # dashed: 6 px on, 4 px off
            assert canvas.along(planned, WALKED) == 0
            page.screenshot(path=str(ARTIFACTS / "dashboard-map-planned.png"), full_page=True)

            # 3. The mission: the walked path is drawn through every pose the page was sent
            #    from the mission's plan on (the server sends the state at 5 Hz, fewer on a
            #    loaded machine: the line joins the poses it got), and those went around the
            #    ball as planned.
            page.click("#run")
            page.wait_for_selector('#result[data-kind="ok"]')
            wait_for(
                lambda: float(page.get_attribute("#map", "data-x") or 0) > 3.9,
                what="the robot to arrive on the map",
            )

            # The page may learn the last pose from the world refresh at the mission's end
            # (GET /api/world, not a frame recorded here): wait for the feed's own state at the
            # goal (it keeps coming at 5 Hz) before comparing the line with the frames.
            # (Playwright's sync API hands over frames only while the test calls into it.)
            def at_goal() -> bool:
                page.wait_for_timeout(20)
                sent = trail_sent(frames)
                return len(sent) >= 3 and math.dist(sent[-1], (4.0, 0.0)) < 0.15

            wait_for(
                at_goal,
                SAFETY,
                "a state frame with the robot at the goal",
                lambda: str(trail_sent(frames)[-3:]),
            )
            canvas = Canvas(page)
            sent = trail_sent(frames)
            # (the robot's marker covers the last 25 cm or so)
            assert canvas.along(sent, WALKED, within=0.04) > 0.9, sent
            assert min(math.dist(p, (3.0, 0.0)) for p in sampled(sent)) > 0.3, sent  # the ball
            page.screenshot(path=str(ARTIFACTS / "dashboard-map-walked.png"), full_page=True)

            # 4. A fresh page, a mission back (no dry run first): its planned path is drawn
            #    from its plan_ready event; stopped early, most of it is still ahead, dashed.
            back = [(p.x, p.y) for p in agent.dry_run("go to x=0, y=0").predicted_path]
            page.reload(wait_until="domcontentloaded")
            page.wait_for_selector('#conn[data-state="live"]')
            page.wait_for_selector('#map[data-grid]:not([data-grid=""])')
            page.fill("#command", "go to x=0, y=0")
            page.click("#run")
            page.wait_for_selector('#steps li[data-status="running"]')
            page.click("#estop")
            page.wait_for_selector('#result[data-kind="error"]')
            assert agent.get_robot_state().x > 1.0  # stopped before the ball: most is ahead
            canvas = Canvas(page)
            assert canvas.along(back, PLANNED) > 0.15
        finally:
            browser.close()
    assert not errors, errors
    assert len(set(grids)) == 1, grids  # the grid never changed: its image was fetched once


def test_the_grid_is_drawn_behind_a_token_too(
    serve: Callable[..., WebServer], tmp_path: Path
) -> None:
    from tests.web.conftest import TOKEN

    sync_playwright = _playwright()
    agent = make_agent()
    server = serve(agent, token=TOKEN)
    with sync_playwright() as p:
        browser = launch(p, tmp_path, DESKTOP)
        try:
            page = browser.new_page()
            page.set_default_timeout(SAFETY * 1000)
            page.goto(server.url + "/#token=" + TOKEN, wait_until="domcontentloaded")
            page.wait_for_selector('#map[data-grid]:not([data-grid=""])')
            assert near(Canvas(page).at(0.5, 1.5), (254, 254, 254), 12)
        finally:
            browser.close()
