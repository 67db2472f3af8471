"""The dashboard map's data over HTTP: the occupancy grid as a PNG placed by /api/map's layout,
fetched again only when it changed; the known objects; the planned path with each mission."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING, Any

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import events as ev
from shadowhound.state import Pose2D
from shadowhound.web.worldmap import grid_png, grid_version
from shadowhound.world import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from tests.web.conftest import finished, make_agent

if TYPE_CHECKING:
    from fastapi.testclient import TestClient

    from shadowhound import RobotAgent


def decode(png: bytes) -> Any:
    from PIL import Image

    image = Image.open(io.BytesIO(png))
    image.load()
    return image


def pixel_at(image: Any, layout: dict[str, Any], x: float, y: float) -> int:
    """The grey level drawn for the point (x, y), by the layout /api/map gives (yaw 0)."""
    col = int((x - layout["origin"]["x"]) / layout["resolution"])
    row = int((y - layout["origin"]["y"]) / layout["resolution"])
    value: int = image.getpixel((col, layout["height"] - 1 - row))
    return value


def test_the_map_names_its_obstacles_before_anything_is_seen(client: TestClient) -> None:
    """The simulator's map is labelled with its scene's names: the dashboard can name every
    blob from the start, while `objects` (what the robot has seen) is still empty."""
    world = client.get("/api/map").json()
    assert world["objects"] == []
    labels = {o["name"]: o for o in world["labels"]}
    assert {"red ball", "blue box", "white fridge", "charging dock", "yellow chair"} <= set(labels)
    assert (labels["charging dock"]["x"], labels["charging dock"]["y"]) == (-3.0, -1.0)
    assert labels["white fridge"]["radius"] > 0


def test_map_gives_the_grid_layout_and_objects_and_the_png_shows_them(client: TestClient) -> None:
    assert client.get("/api/map").json()["objects"] == []  # nothing seen yet
    # Planning a mission looks around first: what is in view becomes known.
    reply = client.post("/api/mission", json={"command": "stand up", "dry_run": True})
    assert reply.status_code == 202, reply.text
    assert finished(client, reply.json()["mission_id"])["success"]
    world = client.get("/api/map").json()
    grid = world["grid"]
    assert grid["resolution"] == 0.05 and grid["width"] > 200 and grid["height"] > 200
    names = {o["name"]: o for o in world["objects"]}
    assert names["red ball"]["x"] == 3.0 and names["red ball"]["y"] == 0.0
    assert names["red ball"]["radius"] > 0 and 0 <= names["red ball"]["confidence"] <= 1

    reply = client.get(grid["url"])
    assert reply.status_code == 200 and reply.headers["content-type"] == "image/png"
    assert len(reply.content) < 20_000  # a 12 m room at 5 cm: far less than its 60k cells
    image = decode(reply.content)
    assert image.mode == "L" and image.size == (grid["width"], grid["height"])
    assert pixel_at(image, grid, 0.0, 0.0) == 254  # free floor where the robot stands
    assert pixel_at(image, grid, 3.0, 0.0) == 0  # the red ball, occupied
    assert pixel_at(image, grid, 2.5, 2.0) == 0  # the blue box
    assert pixel_at(image, grid, 1.0, 1.0) == 254


def test_the_grid_image_is_fetched_again_only_when_it_changed(client: TestClient) -> None:
    grid = client.get("/api/map").json()["grid"]
    first = client.get(grid["url"])
    etag = first.headers["etag"]
    assert etag == f'"{grid["version"]}"'
    again = client.get("/api/map/grid.png", headers={"If-None-Match": etag})
    assert again.status_code == 304 and not again.content
    assert client.get("/api/map").json()["grid"]["version"] == grid["version"]  # unchanged
    stale = client.get("/api/map/grid.png", headers={"If-None-Match": '"00000000"'})
    assert stale.status_code == 200 and stale.content == first.content


def test_without_a_map_there_is_no_grid_and_the_image_says_why() -> None:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    agent = make_agent(sim={"collisions": False})
    try:
        with TestClient(create_app(agent), base_url="http://127.0.0.1") as c:
            world = c.get("/api/map").json()
            assert world["grid"] is None and world["objects"] == []
            reply = c.get("/api/map/grid.png")
            assert reply.status_code == 404 and "no map" in reply.json()["detail"]
    finally:
        agent.cleanup()


def test_each_mission_announces_its_planned_path_around_the_ball(
    client: TestClient, agent: RobotAgent
) -> None:
    seen: list[ev.MissionEvent] = []
    agent.add_listener(lambda e: seen.append(e) if e.kind == ev.PLAN_READY else None)
    result = agent.execute_mission("go to x=4, y=0")
    assert result.success, result.response
    path = seen[-1].data["path"]
    assert path[0] == {"x": 0.0, "y": 0.0} and (path[-1]["x"], path[-1]["y"]) == (4.0, 0.0)
    assert max(abs(p["y"]) for p in path) > 0.3  # around the red ball at (3, 0), not through
    state = agent.get_robot_state()
    assert abs(state.x - 4.0) < 0.1 and abs(state.y) < 0.1


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 30), st.integers(1, 30), st.data())
def test_the_png_is_the_grid_row_for_row_and_the_version_tracks_every_cell(
    width: int, height: int, data: st.DataObject
) -> None:
    values = data.draw(
        st.lists(
            st.sampled_from([UNKNOWN, FREE, 30, 64, 65, OCCUPIED]),
            min_size=width * height,
            max_size=width * height,
        )
    )
    grid = OccupancyGrid.from_msg(
        {
            "info": {
                "width": width,
                "height": height,
                "resolution": 0.1,
                "origin": {"position": {"x": -1.0, "y": 2.0}},
            },
            "data": values,
        }
    )
    image = decode(grid_png(grid))
    assert image.size == (width, height)
    for i, v in enumerate(values):
        col, row = i % width, i // width
        grey = image.getpixel((col, height - 1 - row))
        assert grey == (205 if v == UNKNOWN else 254 - round(v * 2.54))
    version = grid_version(grid)
    i = data.draw(st.integers(0, width * height - 1))
    changed = OccupancyGrid.from_msg(
        {
            "info": {
                "width": width,
                "height": height,
                "resolution": 0.1,
                "origin": {"position": {"x": -1.0, "y": 2.0}},
            },
            "data": [*values[:i], FREE if values[i] else OCCUPIED, *values[i + 1 :]],
        }
    )
    assert grid_version(changed) != version
    moved = OccupancyGrid(width, height, 0.1, Pose2D(-1.0, 2.05, 0.0), bytearray(grid.cells))
    assert grid_version(moved) != version


def test_the_grid_image_needs_the_token_like_every_api_read(agent: RobotAgent) -> None:
    from fastapi.testclient import TestClient

    from shadowhound.web import create_app
    from tests.web.conftest import TOKEN

    with TestClient(create_app(agent, token=TOKEN), base_url="http://127.0.0.1") as c:
        assert c.get("/api/map/grid.png").status_code == 401
        ok = c.get("/api/map/grid.png", headers={"Authorization": f"Bearer {TOKEN}"})
        assert ok.status_code == 200 and ok.content.startswith(b"\x89PNG")
