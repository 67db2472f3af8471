"""Releasing the e-stop is a person's decision. By default no MCP client can, and nothing a model
reads suggests it; with `--allow-release-estop` each release asks the person through the client
(MCP elicitation) and happens only when they agree."""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.mcp.desk import McpDesk, ToolInputError

from .conftest import HttpServer, connect, structured, text_of
from .wire import Wire

ALLOW = "--allow-release-estop"


def test_a_default_server_neither_offers_nor_suggests_releasing_the_estop(http_server):
    server = http_server()
    client = Wire(server.url, "2025-11-25")
    opened = client.send(client.initialize_body())
    init, client.session = opened.result(), opened.headers["mcp-session-id"]
    client.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
    tools = client.send(client.request_body("tools/list")).result()["tools"]
    assert "release_estop" not in {t["name"] for t in tools}
    prompt = client.send(
        client.request_body("prompts/get", {"name": "mission", "arguments": {"task": "sit"}})
    ).result()

    def answer(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
        return client.send(client.tool_call(name, arguments)).messages[-1]

    stop = answer("emergency_stop", {})
    refused = [
        answer("run_mission", {"text": "walk forward 1 meter"}),
        answer("nav_move", {"distance": 0.5}),
        answer("body_sit", {}),
    ]
    release = answer("release_estop", {})
    assert release["error"]["message"].startswith("unknown tool")  # as if it did not exist
    for result in (r["result"] for r in refused):
        assert result["isError"] and "a person must release it" in result["content"][0]["text"]
    assert "until a person releases" in json.dumps(stop)
    seen = json.dumps(
        [init, tools, prompt, stop, refused, answer("get_state", {}), answer("cancel_mission", {})]
    )
    assert "release_estop" not in seen
    assert "call release" not in seen.lower()


def test_the_desk_releases_only_when_built_to():
    settings = ShadowHoundConfig()
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(settings.sim), settings=settings))
    agent.initialize()
    try:
        agent.estop()
        with pytest.raises(ToolInputError, match="a person must release it"):
            McpDesk(agent).release_estop()
        assert agent.estop_latched
        assert McpDesk(agent, allow_release_estop=True).release_estop()["estop_latched"] is False
        assert not agent.estop_latched
    finally:
        agent.cleanup()


# -- with --allow-release-estop ------------------------------------------------------------------


def _person(action: str, release: bool = True) -> Any:
    """An elicitation callback standing in for the person at the client."""
    import mcp_types as types

    asked: list[str] = []

    async def answer(_context: Any, params: Any) -> Any:
        asked.append(params.message)
        content = {"release": release} if action == "accept" else None
        return types.ElicitResult(action=action, content=content)

    answer.asked = asked  # type: ignore[attr-defined]
    return answer


@contextlib.asynccontextmanager
async def latched_client(
    transport: str, http_server: Callable[..., HttpServer], **options: Any
) -> AsyncIterator[Any]:
    """A client of a server that offers release_estop, with the e-stop just latched."""
    if transport == "http":
        server = http_server(ALLOW)
        context = connect("http", url=server.url, **options)
    else:
        context = connect("stdio", server_args=(ALLOW,), **options)
    async with context as client:
        assert structured(await client.call_tool("emergency_stop", {}))["estop_latched"]
        yield client


# "auto" speaks 2026-07-28 (InputRequiredResult, then the call again with the answer); "legacy"
# the handshake era (elicitation/create on the call's stream).
@pytest.mark.parametrize("mode", ["auto", "legacy"])
@pytest.mark.parametrize("transport", ["stdio", "http"])
def test_the_person_agrees_and_the_estop_is_released(transport, mode, http_server):
    person = _person("accept")

    async def scenario() -> None:
        async with latched_client(
            transport, http_server, elicitation_callback=person, mode=mode
        ) as client:
            assert "release_estop" in {t.name for t in (await client.list_tools()).tools}
            released = await client.call_tool("release_estop", {})
            assert not released.is_error, text_of(released)
            assert structured(released)["estop_latched"] is False
            state = structured(await client.call_tool("get_state", {}))
            assert state["estop_latched"] is False and state["robot"]["estopped"] is False
            moved = await client.call_tool("nav_rotate", {"degrees": 10})
            assert not moved.is_error, text_of(moved)

    asyncio.run(scenario())
    assert len(person.asked) == 1 and "release the e-stop" in person.asked[0]


@pytest.mark.parametrize("mode", ["auto", "legacy"])
@pytest.mark.parametrize(
    "person",
    [_person("decline"), _person("cancel"), _person("accept", release=False), None],
    ids=["declined", "cancelled", "said-no", "cannot-ask"],
)
def test_without_the_persons_yes_the_estop_stays_latched(person, mode, http_server):
    options: dict[str, Any] = {"mode": mode}
    if person is not None:
        options["elicitation_callback"] = person

    async def scenario() -> None:
        async with latched_client("http", http_server, **options) as client:
            refused = await client.call_tool("release_estop", {})
            assert refused.is_error and "the e-stop stays latched" in text_of(refused)
            if person is None:
                assert "cannot ask one" in text_of(refused)
            assert structured(await client.call_tool("get_state", {}))["estop_latched"] is True
            still = await client.call_tool("nav_rotate", {"degrees": 10})
            assert still.is_error and "e-stop is latched" in text_of(still)

    asyncio.run(scenario())
