"""Against a real uvicorn server on 127.0.0.1: events over the WebSocket and SSE, the MJPEG
stream, and the e-stop stopping a mission that is really running."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from typing import Any

import httpx
import pytest

from shadowhound.web import WebServer
from tests.images import tiny_jpeg
from tests.web.conftest import SAFETY, TOKEN, finished, make_agent, wait_for

websockets_sync = pytest.importorskip(
    "websockets.sync.client", reason="the websockets package is needed"
)

Serve = Callable[..., WebServer]


def _ws_url(server: WebServer, query: str = "") -> str:
    return server.url.replace("http://", "ws://") + "/ws/status" + query


def _collect(ws: Any, until: str, timeout: float = SAFETY) -> list[dict[str, Any]]:
    """Messages up to and including the first of kind `until`."""
    seen: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        message = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        seen.append(message)
        if message["kind"] == until:
            return seen
    raise AssertionError(f"no {until!r} within {timeout} s; saw {[m['kind'] for m in seen]}")


def test_websocket_reports_a_mission_step_by_step(serve: Serve) -> None:
    server = serve(make_agent(time_scale=0.05), token=TOKEN)
    with websockets_sync.connect(
        _ws_url(server), subprotocols=["shadowhound", f"bearer.{TOKEN}"]
    ) as ws:
        assert json.loads(ws.recv(timeout=SAFETY))["kind"] == "snapshot"
        reply = httpx.post(
            server.url + "/api/mission",
            json={"command": "walk forward 1 meter then turn left 90 degrees"},
            headers={"Authorization": f"Bearer {TOKEN}"},
            timeout=SAFETY,
        )
        mission_id = reply.json()["mission_id"]
        events = [m for m in _collect(ws, "mission_record") if m["kind"] != "state"]
        ws.send("ping")
        assert any(json.loads(ws.recv(timeout=SAFETY))["kind"] == "pong" for _ in range(50))
    kinds = [e["kind"] for e in events]
    assert kinds == [
        "mission_queued",
        "mission_started",
        "plan_ready",
        "step_started",
        "step_finished",
        "step_started",
        "step_finished",
        "mission_finished",
        "mission_record",
    ], kinds
    assert {e["mission_id"] for e in events} == {mission_id}  # the web id throughout
    assert events[-1]["success"] is True
    assert [e["step"]["status"] for e in events if e["kind"] == "step_finished"] == [
        "succeeded",
        "succeeded",
    ]


def test_websocket_events_are_sent_uncompressed_even_to_a_client_offering_deflate(
    serve: Serve,
) -> None:
    """Browsers offer permessage-deflate; accepting it would make the server compress every
    event once per client (and each client inflate it), the fan-out cost growing with the
    audience. The server declines it: an event costs every client the same frame."""
    server = serve(make_agent())
    with websockets_sync.connect(_ws_url(server), compression="deflate") as ws:
        offered = ws.request.headers.get("Sec-WebSocket-Extensions", "") if ws.request else ""
        assert "permessage-deflate" in offered  # the client did offer it
        assert ws.response is not None
        assert "Sec-WebSocket-Extensions" not in ws.response.headers
        assert json.loads(ws.recv(timeout=SAFETY))["kind"] == "snapshot"


def test_websocket_without_token_is_refused(serve: Serve) -> None:
    server = serve(make_agent(), token=TOKEN)
    with (
        pytest.raises(Exception, match="403|1008|rejected"),
        websockets_sync.connect(_ws_url(server)) as ws,
    ):
        ws.recv(timeout=SAFETY)


def test_sse_streams_events_and_replays_after_reconnect(serve: Serve) -> None:
    server = serve(make_agent())
    with httpx.Client(base_url=server.url, timeout=SAFETY) as client:
        first = client.post("/api/mission", json={"command": "turn left 90 degrees"}).json()
        finished(client, first["mission_id"])
        with client.stream("GET", "/api/events?since=0") as stream:
            assert stream.headers["content-type"].startswith("text/event-stream")
            messages = _sse_until(stream, "mission_record")
    replayed = [m for m in messages if m.get("mission_id") == first["mission_id"]]
    assert replayed[0]["kind"] == "mission_queued" and replayed[-1]["kind"] == "mission_record"
    last_id = replayed[-1]["_id"]
    with httpx.Client(base_url=server.url, timeout=SAFETY) as client:
        second = client.post("/api/mission", json={"command": "sit down"}).json()
        finished(client, second["mission_id"])
        with client.stream("GET", "/api/events", headers={"Last-Event-ID": last_id}) as stream:
            messages = _sse_until(stream, "mission_record")
    kinds = [m["kind"] for m in messages if m["kind"] not in ("snapshot", "state")]
    assert kinds[0] == "mission_queued" and messages[-1]["mission_id"] == second["mission_id"]


def _sse_until(stream: httpx.Response, kind: str, timeout: float = SAFETY) -> list[dict[str, Any]]:
    messages: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout
    event_id = ""
    for line in stream.iter_lines():
        if time.monotonic() > deadline:
            break
        if line.startswith("id: "):
            event_id = line[4:]
        elif line.startswith("data: "):
            message = json.loads(line[6:])
            message["_id"] = event_id
            messages.append(message)
            if message["kind"] == kind:
                return messages
    raise AssertionError(f"no {kind!r} event; saw {[m['kind'] for m in messages]}")


def test_mjpeg_passes_jpeg_frames_through_unchanged(serve: Serve) -> None:
    agent = make_agent()
    server = serve(agent)
    frames = [tiny_jpeg(32 + i, 24) for i in range(3)]
    agent.update_camera_image(frames[0])
    received: list[bytes] = []
    with (
        httpx.Client(base_url=server.url, timeout=SAFETY) as client,
        client.stream("GET", "/api/camera/stream?fps=30") as stream,
    ):
        assert stream.headers["content-type"].startswith("multipart/x-mixed-replace")
        buffer, sent = b"", 1
        for chunk in stream.iter_bytes():
            buffer += chunk
            received = _parts(buffer)
            if len(received) >= len(frames):
                break
            if len(received) == sent:  # the newest frame arrived: give the camera another
                agent.update_camera_image(frames[sent])
                sent += 1
    assert received[:3] == frames  # byte for byte, each frame once


def _parts(buffer: bytes) -> list[bytes]:
    parts = []
    for chunk in buffer.split(b"--shadowhound-frame\r\n")[1:]:
        head, _, rest = chunk.partition(b"\r\n\r\n")
        length = int(
            next(
                line.split(b":")[1]
                for line in head.split(b"\r\n")
                if line.lower().startswith(b"content-length")
            )
        )
        if len(rest) >= length:
            parts.append(rest[:length])
    return parts


def test_estop_over_http_stops_a_running_mission(serve: Serve) -> None:
    agent = make_agent(time_scale=0.5)  # real time, twice as fast
    server = serve(agent)
    with httpx.Client(base_url=server.url, timeout=SAFETY) as client:
        # 4 m at 0.1 m/s: 20 s of real time, so the e-stop lands mid-walk on any machine.
        walk = {"command": "walk backward 4 meters at 0.1 m/s"}
        mission = client.post("/api/mission", json=walk).json()
        wait_for(lambda: agent.get_robot_state().vx < -0.05, what="the robot to walk")
        reply = client.post("/api/estop").json()
        assert reply["robot"]["estopped"] is True
        # The hard stop zeroes velocity before the answer is sent.
        assert reply["robot"]["moving"] is False
        record = finished(client, mission["mission_id"])
        assert record["status"] == "stopped" and "e-stop" in record["response"]
        assert -agent.get_robot_state().x < 3.5
        client.post("/api/estop/release")
