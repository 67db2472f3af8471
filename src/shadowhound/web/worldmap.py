"""What the dashboard's map shows of the robot's belief: the occupancy grid and known objects.

The grid goes to the browser as a grayscale PNG (map_server's colours: free white, occupied
black, unknown grey; a 12 m room at 5 cm is a few kB), fetched only when its `version` (a
checksum of the cells and layout) changes; `/api/map` carries the version, the layout to place
the image (origin, resolution, size) and the objects. The PNG is written with zlib alone (no
imaging library), and the last one is kept, so polling clients cost one checksum.
"""

from __future__ import annotations

import struct
import threading
import zlib
from typing import Any

from ..world.grid import OccupancyGrid
from ..world.objects import KnownObject

_UNKNOWN_GREY = 205  # map_server's unknown
# cell byte (0..100 occupancy, 255 unknown; anything else is treated as occupied) -> grey level
_GREYS = bytes(
    254 - round(v * 2.54) if v <= 100 else (_UNKNOWN_GREY if v == 255 else 0) for v in range(256)
)


def grid_version(grid: OccupancyGrid) -> str:
    """Changes whenever a cell, the size, the resolution or the origin changes."""
    o = grid.origin
    layout = f"{grid.width}x{grid.height}@{grid.resolution}:{o.x},{o.y},{o.yaw}".encode()
    return f"{zlib.crc32(grid.cells, zlib.crc32(layout)):08x}"


def grid_png(grid: OccupancyGrid) -> bytes:
    """The grid as an 8-bit grayscale PNG, the top image row the grid's last row (largest y
    in the grid's own frame), so the image is the map seen from above."""
    grey = bytes(grid.cells).translate(_GREYS)
    w = grid.width
    rows = b"".join(b"\x00" + grey[r * w : (r + 1) * w] for r in range(grid.height - 1, -1, -1))
    return b"".join(
        [
            b"\x89PNG\r\n\x1a\n",
            _chunk(b"IHDR", struct.pack(">IIBBBBB", w, grid.height, 8, 0, 0, 0, 0)),
            _chunk(b"IDAT", zlib.compress(rows, 6)),
            _chunk(b"IEND", b""),
        ]
    )


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data))
        + kind
        + data
        + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def grid_layout(grid: OccupancyGrid, version: str) -> dict[str, Any]:
    """Where the PNG goes: cell (0, 0)'s outer corner at `origin`, `resolution` m per pixel."""
    o = grid.origin
    return {
        "version": version,
        "width": grid.width,
        "height": grid.height,
        "resolution": grid.resolution,
        "origin": {"x": round(o.x, 4), "y": round(o.y, 4), "yaw": round(o.yaw, 6)},
        "url": f"/api/map/grid.png?v={version}",
    }


def object_dicts(objects: tuple[KnownObject, ...]) -> list[dict[str, Any]]:
    return [
        {
            "name": o.name,
            "x": round(o.x, 3),
            "y": round(o.y, 3),
            "radius": round(o.radius, 3),
            "confidence": round(o.confidence, 3),
            "stamp": round(o.stamp, 3),
        }
        for o in objects
    ]


class GridImages:
    """The last grid's PNG, by version (one per app)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._last: tuple[str, bytes] | None = None

    def png(self, grid: OccupancyGrid, version: str) -> bytes:
        with self._lock:
            if self._last is not None and self._last[0] == version:
                return self._last[1]
        data = grid_png(grid)
        with self._lock:
            self._last = (version, data)
        return data
