"""`shadowhound mcp` end to end: the SDK's own client over stdio and Streamable HTTP against the
server as a separate process, judged by the simulated robot's state."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import io
import json
import math
import subprocess
import sys
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest

from shadowhound.mcp.catalogue import skill_schema
from shadowhound.skills import default_registry

from .conftest import HttpServer, connect, server_env, structured, text_of

TRANSPORTS = ["stdio", "http"]
REAL_TIME = 1.0  # the robot takes real seconds, so there is a mission to stop
# 20 s of walking: a stop pressed once it walks lands mid-walk on any machine.
SLOW_WALK = "walk forward 2 meters at 0.1 m/s"


@contextlib.asynccontextmanager
async def client_for(
    transport: str, http_server: Callable[..., HttpServer], time_scale: float = 0.0, **options: Any
) -> AsyncIterator[Any]:
    if transport == "http":
        server = http_server(time_scale=time_scale)
        async with connect("http", url=server.url, **options) as client:
            yield client
    else:
        async with connect("stdio", time_scale=time_scale, **options) as client:
            yield client


async def robot(client: Any) -> dict[str, Any]:
    return structured(await client.call_tool("get_state", {}))["robot"]


async def wait_for_step(progress: list[str], skill: str, timeout: float = 60.0) -> None:
    """Until a progress message says `skill` started."""
    for _ in range(int(timeout / 0.02)):
        if any(skill in m and ":" not in m for m in progress):
            return
        await asyncio.sleep(0.02)
    raise AssertionError(f"{skill} never started; progress: {progress}")


async def walking(client: Any) -> dict[str, Any]:
    """The robot's state once it has walked a few centimetres (60 s at most)."""
    for _ in range(3000):
        if (state := await robot(client))["x"] > 0.05:
            return state
        await asyncio.sleep(0.02)
    raise AssertionError("the robot never walked")


def run(coro: Any) -> Any:
    return asyncio.run(coro)


# -- listing ---------------------------------------------------------------------------------


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_lists_tools_from_the_registry_resources_and_the_prompt(transport, http_server):
    async def scenario() -> None:
        async with client_for(transport, http_server) as client:
            tools = {t.name: t for t in (await client.list_tools()).tools}
            for name in (
                "run_mission",
                "plan_mission",
                "get_state",
                "get_camera_image",
                "emergency_stop",
                "cancel_mission",
                "history",
            ):
                assert name in tools
            assert "release_estop" not in tools  # a person's decision (--allow-release-estop)
            for skill in default_registry():  # one tool per skill, the registry's schema
                tool = tools[skill.tool_name]
                assert tool.input_schema == skill_schema(skill)
                assert tool.description == skill.description
            # ... where a number may also be text with a unit ("50 cm"), as the registry reads
            # it; its bounds stay (they apply to numbers).
            distance = tools["nav_move"].input_schema["properties"]["distance"]
            assert distance["type"] == ["number", "string"] and distance["maximum"] == 1000
            speed = tools["nav_move"].input_schema["properties"]["speed"]["anyOf"]
            assert speed[0]["type"] == ["number", "string"] and speed[1] == {"type": "null"}
            laps = tools["nav_patrol"].input_schema["properties"]["laps"]["anyOf"]
            assert laps[0]["type"] == ["integer", "string"] and laps[1] == {"type": "null"}
            assert (
                tools["body_sport"].input_schema
                == default_registry().get("body.sport").parameters_schema()
            )  # no numbers: the registry's schema as it is
            uris = {str(r.uri) for r in (await client.list_resources()).resources}
            assert {
                "shadowhound://skills",
                "shadowhound://places",
                "shadowhound://missions/last",
            } <= uris
            skills = json.loads(
                (await client.read_resource("shadowhound://skills")).contents[0].text
            )
            assert [s["name"] for s in skills] == default_registry().names
            await client.call_tool("places_remember", {"name": "dock"})
            places = json.loads(
                (await client.read_resource("shadowhound://places")).contents[0].text
            )
            assert places["dock"]["x"] == 0.0 and places["dock"]["y"] == 0.0
            prompt = await client.get_prompt("mission", {"task": "fetch the ball"})
            assert "fetch the ball" in prompt.messages[0].content.text

    run(scenario())


# -- missions ----------------------------------------------------------------------------------


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_run_mission_moves_the_robot_and_reports_each_step(transport, http_server):
    progress: list[tuple[float, float | None, str | None]] = []

    async def on_progress(done: float, total: float | None, message: str | None) -> None:
        progress.append((done, total, message))

    async def scenario() -> dict[str, Any]:
        async with client_for(transport, http_server) as client:
            result = await client.call_tool(
                "run_mission",
                {"text": "walk forward 1 meter and turn left 90 degrees"},
                progress_callback=on_progress,
            )
            assert not result.is_error, text_of(result)
            state = await robot(client)
            assert state["x"] == pytest.approx(1.0, abs=0.05)
            assert state["yaw_deg"] == pytest.approx(90.0, abs=2.0)
            last = json.loads(
                (await client.read_resource("shadowhound://missions/last")).contents[0].text
            )
            assert last["mission_id"] == structured(result)["mission_id"]
            return structured(result)

    answer = run(scenario())
    assert answer["success"] is True and answer["status"] == "succeeded"
    steps = answer["steps"]
    assert [s["skill"] for s in steps][-2:] == ["nav.move", "nav.rotate"]
    # One notification when the plan is ready, then a start and an end for every step.
    assert len(progress) == 1 + 2 * len(steps)
    assert progress[-1][0] == progress[-1][1] == len(steps)
    assert [p[0] for p in progress] == sorted(p[0] for p in progress)


def test_run_mission_answers_the_same_data_as_run_json(http_server):
    mission = "walk forward 1 meter"
    cli = subprocess.run(
        [sys.executable, "-m", "shadowhound", "run", mission, "--json"],
        env=server_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    expected = json.loads(cli.stdout)

    async def scenario() -> dict[str, Any]:
        async with client_for("stdio", http_server) as client:
            return structured(await client.call_tool("run_mission", {"text": mission}))

    answer = run(scenario())
    assert set(answer) == set(expected) - {"exit_code"}
    assert [(s["skill"], s["args"], s["status"]) for s in answer["steps"]] == [
        (s["skill"], s["args"], s["status"]) for s in expected["steps"]
    ]
    assert answer["robot"]["x"] == pytest.approx(expected["robot"]["x"], abs=1e-6)


def test_plan_mission_moves_nothing(http_server):
    async def scenario() -> None:
        async with client_for("stdio", http_server) as client:
            plan = structured(
                await client.call_tool("plan_mission", {"text": "walk forward 2 meters"})
            )
            assert plan["dry_run"] is True and plan["success"] is True
            assert plan["predicted_path"][-1]["x"] == pytest.approx(2.0, abs=0.01)
            assert (await robot(client))["x"] == 0.0

    run(scenario())


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_camera_image_is_a_downscaled_jpeg(transport, http_server):
    from PIL import Image

    async def scenario() -> Any:
        async with client_for(transport, http_server) as client:
            return await client.call_tool("get_camera_image", {})

    result = run(scenario())
    image = next(c for c in result.content if c.type == "image")
    assert image.mime_type == "image/jpeg"
    data = base64.b64decode(image.data)
    assert data[:2] == b"\xff\xd8"
    picture = Image.open(io.BytesIO(data))
    assert picture.format == "JPEG" and max(picture.size) <= 512


# -- the governor, approvals ----------------------------------------------------------------------


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_skill_call_over_the_limit_is_refused_with_the_governors_message(transport, http_server):
    async def scenario() -> None:
        async with client_for(transport, http_server) as client:
            result = await client.call_tool("nav_move", {"distance": 100})
            assert result.is_error
            assert "exceeds the limit of 5 m per step (safety.max_step_distance)" in text_of(result)
            assert (await robot(client))["x"] == 0.0
            ok = await client.call_tool("nav_move", {"distance": "50 cm"})
            assert not ok.is_error, text_of(ok)
            assert (await robot(client))["x"] == pytest.approx(0.5, abs=0.03)

    run(scenario())


def _elicitation(action: str, approve: bool = True) -> Any:
    import mcp_types as types

    asked: list[str] = []

    async def answer(_context: Any, params: Any) -> Any:
        asked.append(params.message)
        content = {"approve": approve} if action == "accept" else None
        return types.ElicitResult(action=action, content=content)

    answer.asked = asked  # type: ignore[attr-defined]
    return answer


# "auto" speaks the 2026-07-28 protocol (the server answers InputRequiredResult and the client
# calls again with the answer); "legacy" the handshake era (the server sends elicitation/create).
@pytest.mark.parametrize("transport", TRANSPORTS)
@pytest.mark.parametrize("mode", ["auto", "legacy"])
def test_risky_call_asks_the_person_accepted_and_declined(transport, mode, http_server):
    accept, decline = _elicitation("accept"), _elicitation("decline")

    async def scenario() -> tuple[Any, Any]:
        async with client_for(
            transport, http_server, elicitation_callback=accept, mode=mode
        ) as client:
            yes = await client.call_tool("body_sport", {"trick": "front_flip"})
        async with client_for(
            transport, http_server, elicitation_callback=decline, mode=mode
        ) as client:
            no = await client.call_tool("body_sport", {"trick": "front_flip"})
        return yes, no

    yes, no = run(scenario())
    assert not yes.is_error, text_of(yes)
    assert structured(yes)["steps"][0]["status"] == "succeeded"
    assert "front_flip is a risky trick" in accept.asked[0]
    assert no.is_error and "declined by the person" in text_of(no)
    assert structured(no)["steps"][0]["status"] == "skipped"


def test_risky_call_is_refused_when_the_client_cannot_ask(http_server):
    async def scenario() -> Any:
        async with client_for("stdio", http_server) as client:
            return await client.call_tool("body_sport", {"trick": "front_flip"})

    result = run(scenario())
    assert result.is_error
    assert "cannot ask a person (it does not support elicitation)" in text_of(result)


# -- stopping ------------------------------------------------------------------------------------


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_emergency_stop_mid_mission_stops_the_robot_and_latches(transport, http_server):
    progress: list[str] = []

    async def on_progress(_done: float, _total: float | None, message: str | None) -> None:
        progress.append(message or "")

    async def scenario() -> None:
        async with client_for(transport, http_server, time_scale=REAL_TIME) as client:
            mission = asyncio.create_task(
                client.call_tool("run_mission", {"text": SLOW_WALK}, progress_callback=on_progress)
            )
            await wait_for_step(progress, "nav.move")
            await walking(client)
            stop = structured(await client.call_tool("emergency_stop", {}))
            assert stop["estop_latched"] is True
            # Stopped before the answer was written: the state in it was read after the stop.
            assert stop["robot"]["moving"] is False and stop["robot"]["estopped"] is True
            stopped = await robot(client)
            result = structured(await mission)
            assert result["status"] == "stopped" and "e-stop" in result["response"]
            assert 0.05 < stopped["x"] < 3.0
            await asyncio.sleep(0.5)
            after = await robot(client)
            assert after["moving"] is False
            assert after["x"] == pytest.approx(stopped["x"], abs=0.02)  # it stayed stopped
            latched = await client.call_tool("run_mission", {"text": "walk forward 1 meter"})
            assert latched.is_error and "e-stop is latched" in text_of(latched)
            assert "a person must release it" in text_of(latched)

    run(scenario())


def test_patrol_until_i_say_stop_ends_on_cancel_mission_as_a_success(http_server):
    """Issue 26: "patrol until I say stop" is stopped by a person's cancel_mission; the stop is
    what the mission waited for, so it succeeds, says why, and the robot stands still."""
    progress: list[str] = []

    async def on_progress(_done: float, _total: float | None, message: str | None) -> None:
        progress.append(message or "")

    async def scenario() -> None:
        async with client_for("http", http_server, time_scale=REAL_TIME) as client:
            mission = asyncio.create_task(
                client.call_tool(
                    "run_mission",
                    {"text": "patrol until I say stop"},
                    progress_callback=on_progress,
                )
            )
            await wait_for_step(progress, "nav.patrol")
            for _ in range(3000):  # walking: its odometer counts (60 s at most)
                if (await robot(client))["distance_travelled"] > 0.1:
                    break
                await asyncio.sleep(0.02)
            else:
                raise AssertionError("the patrol never walked")
            cancel = structured(await client.call_tool("cancel_mission", {}))
            assert cancel["cancelled"] is True
            result = structured(await mission)
            assert result["success"] is True and result["status"] == "succeeded", result
            assert "stopped: you said stop (until I say stop)" in result["response"]
            for _ in range(3000):  # it brakes within its deceleration limit, then stands
                if not (await robot(client))["moving"]:
                    break
                await asyncio.sleep(0.02)
            else:
                raise AssertionError("the robot kept moving after the stop")

    run(scenario())


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_a_second_mission_is_refused_busy_never_queued(transport, http_server):
    progress: list[str] = []

    async def on_progress(_done: float, _total: float | None, message: str | None) -> None:
        progress.append(message or "")

    async def scenario() -> None:
        async with client_for(transport, http_server, time_scale=REAL_TIME) as client:
            first = asyncio.create_task(
                client.call_tool("run_mission", {"text": SLOW_WALK}, progress_callback=on_progress)
            )
            await wait_for_step(progress, "nav.move")
            second = await client.call_tool("run_mission", {"text": "turn left 90 degrees"})
            skill = await client.call_tool("nav_rotate", {"degrees": 90})
            assert second.is_error and text_of(second).startswith("busy:")
            assert skill.is_error and text_of(skill).startswith("busy:")
            assert structured(await client.call_tool("cancel_mission", {}))["cancelled"] is True
            assert structured(await first)["status"] == "stopped"
            state = structured(await client.call_tool("get_state", {}))
            assert state["busy"] is False  # nothing was queued behind it (it would be busy)
            assert state["robot"]["yaw"] == 0.0  # neither refused call ran
            history = structured(await client.call_tool("history", {"limit": 10}))["missions"]
            assert history[0]["mission"] == SLOW_WALK  # a queued one would be on record
            assert not {"turn left 90 degrees", "nav.rotate(degrees=90)"} & {
                m["mission"] for m in history
            }

    run(scenario())


def test_http_client_going_away_mid_mission_stops_the_robot(http_server):
    server = http_server(time_scale=REAL_TIME)
    progress: list[str] = []

    async def on_progress(_done: float, _total: float | None, message: str | None) -> None:
        progress.append(message or "")

    async def scenario() -> None:
        async with connect("http", url=server.url) as client:
            mission = asyncio.create_task(
                client.call_tool("run_mission", {"text": SLOW_WALK}, progress_callback=on_progress)
            )
            await wait_for_step(progress, "nav.move")
            await walking(client)
            mission.cancel()  # the client gives up on the call and leaves
            with contextlib.suppress(asyncio.CancelledError):
                await mission
        async with connect("http", url=server.url) as client:
            for _ in range(3000):  # the server notices the client gone, ends its mission
                if not structured(await client.call_tool("get_state", {}))["busy"]:
                    break
                await asyncio.sleep(0.02)
            else:
                raise AssertionError("the mission of the client that left ran on")
            for _ in range(1200):  # the simulator brakes at its deceleration limit
                if not (first := await robot(client))["moving"]:
                    break
                await asyncio.sleep(0.05)
            assert first["moving"] is False
            await asyncio.sleep(0.6)
            later = await robot(client)
            assert later["x"] == pytest.approx(first["x"], abs=1e-3)  # and stays stopped
            assert later["x"] < 1.0  # far from the 2 m asked

    run(scenario())
    assert server.alive()


# -- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_bad_arguments_get_mcp_errors_and_the_server_lives_on(transport, http_server):
    from mcp.shared.exceptions import MCPError

    cases = [
        ("nav_move", {"distance": "far"}, "is not a length"),
        ("nav_move", {"distance": math.nan}, "distance"),
        ("nav_move", {"distance": 1, "speed": [1]}, "speed"),
        ("nav_move", {"metres": 1}, "unknown argument 'metres'"),
        ("run_mission", {"text": 42}, "must be a string"),
        ("run_mission", {"text": "x" * 100_000}, "the limit is"),
        ("run_mission", {"text": "  "}, "empty"),
        ("run_mission", {"text": "sit", "dry_run": "yes"}, "dry_run"),
        ("run_mission", {}, "missing required argument 'text'"),
        ("history", {"limit": -3}, "limit"),
        ("body_sport", {"trick": "somersault"}, "trick"),
    ]

    async def scenario() -> None:
        async with client_for(transport, http_server) as client:
            for tool, args, expected in cases:
                result = await client.call_tool(tool, args)
                assert result.is_error, (tool, args)
                assert expected in text_of(result), (tool, args, text_of(result))
            with pytest.raises(MCPError, match="unknown tool 'fly'"):
                await client.call_tool("fly", {})
            state = await robot(client)
            assert (state["x"], state["y"], state["yaw"]) == (0.0, 0.0, 0.0)

    run(scenario())
