"""`create_app(agent)`: the dashboard page and the HTTP API around one RobotAgent.

The app drives the agent only through its public API and one `MissionWorker` (through the
mission desk). It never binds a socket itself; `serve()` (server.py) or a host (the ROS node)
runs it with uvicorn.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator, Iterable
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException

from .. import __version__
from ..agent import RobotAgent
from ..serving import LOOPBACK_HOSTS
from ..worker import MissionWorker
from . import api, live, speech, teleop
from .desk import MissionDesk
from .estop import EstopLane
from .feed import EventFeed
from .frames import FrameCache
from .models import MAX_BODY
from .openapi import document_answers
from .responses import StrictJSON
from .security import BodyLimit, Gate, scrubber, secret_values

log = logging.getLogger(__name__)

STATIC_DIR = Path(__file__).resolve().parent / "static"
# The page loads only its own files; images may be data: or blob: URLs drawn by the script.
_PAGE_POLICY = (
    "default-src 'self'; img-src 'self' data: blob:; connect-src 'self'; "
    "style-src 'self'; script-src 'self'; frame-ancestors 'none'; base-uri 'none'"
)


def create_app(
    agent: RobotAgent,
    *,
    token: str | None = None,
    worker: MissionWorker | None = None,
    allowed_hosts: Iterable[str] | None = LOOPBACK_HOSTS,
    max_body: int = MAX_BODY,
    approvals: bool = True,
    state_hz: float = 5.0,
    secrets: Iterable[str] = (),
) -> FastAPI:
    """The FastAPI app for `agent` (initialized here if it is not yet).

    - `token`: required on every /api/ and /ws/ request but `GET /api/health` (see security.py).
    - `worker`: an existing MissionWorker to share (the desk registers its own listeners on
      it); by default the app makes one and stops it at shutdown.
    - `allowed_hosts`: Host names accepted without a token (None: any).
    - `approvals`: the page can approve risky plans, so the agent may ask instead of refusing.
    - `secrets`: further values to mask in answers (the token and the API key always are).
    """
    agent.initialize()
    if approvals:
        agent.enable_approvals()
    hidden = [*secret_values(token, agent.settings.llm.api_key_env), *secrets]
    feed = EventFeed(scrub=scrubber(hidden))
    desk = MissionDesk(agent, feed, worker=worker)
    web = api.WebContext(agent, desk, feed, FrameCache(agent), auth=token is not None)
    ears = speech.Ears.open(agent.settings.speech)

    @contextlib.asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        if agent.settings.speech.base_url.strip():
            ears.readers.warm()  # no recording waits for its reader to start
        ticker = asyncio.create_task(live.publish_state(web, state_hz))
        try:
            yield
        finally:
            ticker.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await ticker
            ears.close()
            desk.close()

    app = FastAPI(
        title="ShadowHound",
        version=__version__,
        lifespan=lifespan,
        default_response_class=StrictJSON,
        description="Missions, live progress, camera, map and e-stop for a "
        "quadruped robot. Mutating requests need `Authorization: Bearer "
        "<token>` when the server has a token.",
    )
    app.state.web = web
    app.state.ears = ears  # recordings are read and transcribed off the event loop
    app.include_router(api.router)
    app.include_router(live.router)
    app.include_router(speech.router)
    app.include_router(teleop.router)
    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    _add_page(app)
    _add_error_handlers(app)
    app.add_middleware(EstopLane, estop=desk.estop)  # inside the gate: checked, then first
    hearing = agent.settings.speech
    app.add_middleware(
        Gate,
        token=token,
        allowed_hosts=allowed_hosts,
        max_body=max_body,
        secrets=hidden,
        limits={
            speech.PATH: BodyLimit(
                hearing.max_bytes,
                f"the recording is larger than the limit of {hearing.max_bytes} bytes "
                "(speech.max_bytes)",
                hearing.upload_timeout,
                f"the recording did not arrive within {hearing.upload_timeout:g} s "
                "(speech.upload_timeout): send it again on a faster link",
            )
        },
    )
    _document(
        app, token=token is not None, checks_hosts=allowed_hosts is not None, max_body=max_body
    )
    return app


def _document(app: FastAPI, **gate: Any) -> None:
    """Make /openapi.json say what this app really sends (see openapi.py)."""
    build = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            app.openapi_schema = document_answers(build(), **gate)
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


def _add_page(app: FastAPI) -> None:
    @app.get("/", include_in_schema=False)
    async def index() -> FileResponse:
        return FileResponse(
            STATIC_DIR / "index.html",
            headers={"Content-Security-Policy": _PAGE_POLICY, "Cache-Control": "no-cache"},
        )


def _add_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(RequestValidationError)
    async def invalid(_request: Request, exc: RequestValidationError) -> StrictJSON:
        # Say what was wrong without echoing the input back (it may be large or private).
        problems = [
            {"where": ".".join(str(p) for p in e.get("loc", ())), "problem": e["msg"]}
            for e in exc.errors()
        ]
        text = "; ".join(f"{p['where']}: {p['problem']}" for p in problems)
        return StrictJSON(
            {"detail": f"invalid request: {text}", "problems": problems}, status_code=422
        )

    @app.exception_handler(StarletteHTTPException)
    async def http_error(_request: Request, exc: StarletteHTTPException) -> StrictJSON:
        return StrictJSON(
            {"detail": exc.detail},
            status_code=exc.status_code,
            headers=getattr(exc, "headers", None),
        )

    @app.exception_handler(Exception)
    async def crashed(request: Request, exc: Exception) -> StrictJSON:
        log.exception("request %s %s failed", request.method, request.url.path)
        return StrictJSON(
            {"detail": "internal error; the server log has the details"}, status_code=500
        )
