"""`StrictJSON`: every JSON answer of the dashboard's API, written by `jsonout`.

Starlette's JSONResponse refuses a number that is not finite (a 500 for the whole answer); a
robot whose odometry lies would take /api/status down with it. This one writes such a number
as null, so the answer still says everything else that is known.
"""

from __future__ import annotations

from typing import Any

from fastapi.responses import JSONResponse

from .. import jsonout


class StrictJSON(JSONResponse):
    """A JSONResponse whose body is strict JSON: numbers that are not finite are null."""

    def render(self, content: Any) -> bytes:
        return jsonout.dumps(content, ensure_ascii=False, separators=(",", ":")).encode("utf-8")
