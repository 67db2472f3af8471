"""Live routes: camera (latest image and MJPEG), events over SSE and the WebSocket, state ticks."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
from collections.abc import AsyncIterator
from typing import Any, Literal

from fastapi import APIRouter, HTTPException, Query, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import Response, StreamingResponse

from ..errors import FrameUnavailable
from .api import WebContext, ctx, current_status
from .feed import Packet, Subscription
from .frames import BOUNDARY, frame_summary, mjpeg_part
from .models import Problem
from .security import WS_PROTOCOL

router = APIRouter()
_NO_STORE = {"Cache-Control": "no-store"}
STREAM_SHARE_SECONDS = 1 / 60  # stream clients asking within this share one frame
LAGGED_CLOSE = 1013  # "try again later": the client fell behind and should reconnect
# Messages a WebSocket client sends per wake-up: each is a frame and a write of its own (an
# event stream joins what is waiting into one write), so a backlog goes out a few at a time and
# one loop turn of the fan-out stays short (feed.py).
WS_BATCH = 4
SSE_BATCH = 16  # events joined into one SSE write per wake-up (bounds a client's turn)


@router.get(
    "/api/camera/latest",
    tags=["camera"],
    responses={200: {"content": {"image/jpeg": {}, "image/png": {}}}, 503: {"model": Problem}},
)
async def camera_latest(request: Request, format: Literal["image", "json"] = "image") -> Any:
    """The latest camera image as JPEG (PNG only without Pillow). `?format=json` (or
    `Accept: application/json`) gives the original ShadowHound answer: base64 in JSON."""
    web = ctx(request)
    accept = request.headers.get("accept", "")
    as_json = format == "json" or ("application/json" in accept and "image/" not in accept)
    try:
        frame = web.frames.get()
    except FrameUnavailable as exc:
        if as_json:
            return {"image": None, "available": False, "reason": str(exc)}
        raise HTTPException(503, str(exc)) from None
    if as_json:
        return {
            "image": base64.b64encode(frame.data).decode("ascii"),
            "available": True,
            **frame_summary(frame),
        }
    return Response(
        frame.data,
        media_type=frame.content_type,
        headers={**_NO_STORE, "X-Timestamp": f"{frame.stamp:.6f}"},
    )


@router.get(
    "/api/camera/stream",
    tags=["camera"],
    responses={
        200: {"content": {f"multipart/x-mixed-replace; boundary={BOUNDARY}": {}}},
        503: {"model": Problem},
    },
)
async def camera_stream(
    request: Request, fps: float = Query(15.0, gt=0, le=30)
) -> StreamingResponse:
    """MJPEG (multipart/x-mixed-replace) at up to `fps` frames a second. JPEG frames from the
    camera pass through unchanged; each new frame is sent once."""
    web = ctx(request)
    try:
        web.frames.get()
    except FrameUnavailable as exc:
        raise HTTPException(503, str(exc)) from None
    return StreamingResponse(
        _mjpeg(web, 1.0 / fps),
        media_type=f"multipart/x-mixed-replace; boundary={BOUNDARY}",
        headers=_NO_STORE,
    )


async def _mjpeg(web: WebContext, interval: float) -> AsyncIterator[bytes]:
    last = None
    while True:
        try:
            frame = web.frames.get(max_age=STREAM_SHARE_SECONDS)
        except FrameUnavailable:
            frame = None
        if frame is not None and frame is not last:
            last = frame
            yield mjpeg_part(frame)
            await asyncio.sleep(interval)
        else:  # nothing new yet: look again soon rather than a whole interval later
            await asyncio.sleep(interval / 4)


@router.get("/api/events", tags=["live"], responses={200: {"content": {"text/event-stream": {}}}})
async def events(
    request: Request, since: int | None = Query(None, ge=0, le=2**53)
) -> StreamingResponse:
    """Server-sent events: a `snapshot`, then every event as `id: <seq>` + JSON `data` (the
    kind is inside). Reconnecting with `Last-Event-ID` (or `?since=`) replays what was missed.
    A client more than 500 events behind gets a `lagged` message and the stream ends."""
    web = ctx(request)
    last_id = request.headers.get("last-event-id", "")
    if since is None and last_id.isdigit():
        since = int(last_id)
    subscription, missed = web.feed.subscribe(asyncio.get_running_loop(), since)
    return StreamingResponse(
        _sse(web, subscription, missed),
        media_type="text/event-stream",
        headers={**_NO_STORE, "X-Accel-Buffering": "no"},
    )


async def _sse(
    web: WebContext, subscription: Subscription, missed: list[Packet]
) -> AsyncIterator[str]:
    try:
        yield "retry: 2000\n\n"
        yield f"data: {web.feed.encode(_snapshot(web))}\n\n"
        if missed:
            yield "".join(_sse_event(p) for p in missed)
        while not subscription.lagged:
            packets = await subscription.next(timeout=15.0, limit=SSE_BATCH)
            if packets:  # one write for all that is waiting
                yield "".join(_sse_event(p) for p in packets)
            else:
                yield ": keep-alive\n\n"  # lets proxies and clients see the stream is alive
        # Lagged: the stream ends here and EventSource reconnects with Last-Event-ID.
    finally:
        subscription.close()


def _sse_event(packet: Packet) -> str:
    # Every feed message is numbered; the lag notice is not (a reconnect resumes before it).
    head = f"id: {packet.seq}\n" if packet.seq is not None else ""
    return f"{head}data: {packet.text}\n\n"


@router.websocket("/ws/status")
async def ws_status(websocket: WebSocket) -> None:
    """A `snapshot`, then every event as JSON text. Send "ping" to get {"kind": "pong"}.
    A client more than 500 events behind gets a `lagged` message, then close code 1013."""
    web: WebContext = websocket.app.state.web
    offered = websocket.scope.get("subprotocols", [])
    await websocket.accept(subprotocol=WS_PROTOCOL if WS_PROTOCOL in offered else None)
    subscription, _ = web.feed.subscribe(asyncio.get_running_loop())
    reader = asyncio.create_task(_ws_read(websocket, subscription))
    try:
        await websocket.send_text(web.feed.encode(_snapshot(web)))
        while not reader.done() and not subscription.lagged:
            for packet in await subscription.next(timeout=5.0, limit=WS_BATCH):
                await websocket.send_text(packet.text)
        if subscription.lagged:  # told in the last message; the page reconnects
            await websocket.close(
                code=LAGGED_CLOSE, reason="lagged: reconnect and read /api/status"
            )
    except (WebSocketDisconnect, RuntimeError, OSError):
        pass  # the client went away while we were sending; nothing to clean but below
    finally:
        subscription.close()
        reader.cancel()
        with contextlib.suppress(asyncio.CancelledError, WebSocketDisconnect, RuntimeError):
            await reader


async def _ws_read(websocket: WebSocket, subscription: Subscription) -> None:
    """Answer pings through the subscription, so only one task ever sends on the socket."""
    try:
        while True:
            text = await websocket.receive_text()
            if text.strip() == "ping" or _json_type(text) == "ping":
                subscription.deliver({"kind": "pong"})
    except WebSocketDisconnect:
        subscription.wake()  # the sender stops waiting for events at once


def _json_type(text: str) -> Any:
    try:
        parsed = json.loads(text)
    except ValueError:
        return None
    return parsed.get("type") if isinstance(parsed, dict) else None


def _snapshot(web: WebContext) -> dict[str, Any]:
    return {
        "kind": "snapshot",
        "status": current_status(web),
        "missions": web.desk.missions(20),
        "seq": None,
    }


async def publish_state(web: WebContext, hz: float) -> None:
    """Robot state at `hz` while anyone listens (the map and progress bar follow it)."""
    while True:
        await asyncio.sleep(1.0 / hz)
        if web.feed.clients:
            web.feed.publish("state", current_status(web), keep=False)
