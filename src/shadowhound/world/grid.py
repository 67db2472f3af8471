"""The occupancy grid: what the robot believes about each 5 cm square of floor.

The layout is nav_msgs/OccupancyGrid's, so a map from slam_toolbox or map_server converts
without reinterpretation: row-major cells, row 0 at the origin, column index growing along the
origin's x axis; each cell is -1 (unknown) or an occupancy probability 0..100. `origin` is the
pose of cell (0, 0)'s outer corner in the map/odom frame.

Cells are kept in a bytearray (unknown stored as 255, the unsigned byte of int8 -1) so the
hot loops (inflation, scan updates, the planner) run on C-level slice and translate operations
with the standard library only; `import shadowhound` stays free of numpy.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..errors import GridError
from ..state import Pose2D, not_finite

UNKNOWN = -1
FREE = 0
OCCUPIED = 100
OCCUPIED_THRESHOLD = 65  # map_server's default occupied_thresh (0.65), in percent
DEFAULT_RESOLUTION = 0.05  # metres per cell
MAX_CELLS = 25_000_000  # 250 m x 250 m at 5 cm: beyond this a map is a mistake, not a house

_UNKNOWN_BYTE = 255
_FAR = float(2**40)  # cells: beyond any map (MAX_CELLS), yet a whole number a float holds


@dataclass(frozen=True)
class Cell:
    """A grid cell: column (along the origin's x) and row (along its y)."""

    col: int
    row: int


@dataclass
class OccupancyGrid:
    """A 2D occupancy grid in the nav_msgs/OccupancyGrid layout (see the module docstring)."""

    width: int
    height: int
    resolution: float = DEFAULT_RESOLUTION
    origin: Pose2D = field(default_factory=Pose2D)
    cells: bytearray = field(default_factory=bytearray)  # empty: all unknown

    def __post_init__(self) -> None:
        if not (isinstance(self.width, int) and isinstance(self.height, int)):
            raise GridError(
                f"width and height must be integers, got {self.width!r}, {self.height!r}"
            )
        if self.width <= 0 or self.height <= 0 or self.width * self.height > MAX_CELLS:
            raise GridError(
                f"grid size must be positive and at most {MAX_CELLS} cells, got "
                f"{self.width} x {self.height}"
            )
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise GridError(f"resolution must be > 0 metres per cell, got {self.resolution}")
        if not all(math.isfinite(v) for v in (self.origin.x, self.origin.y, self.origin.yaw)):
            raise GridError(f"origin must be finite, got {self.origin}")
        n = self.width * self.height
        if not self.cells:
            self.cells = bytearray([_UNKNOWN_BYTE]) * n
        elif len(self.cells) != n:
            raise GridError(f"cells has {len(self.cells)} values, expected width * height = {n}")
        self._cos = math.cos(self.origin.yaw)
        self._sin = math.sin(self.origin.yaw)

    # -- construction -----------------------------------------------------------------------

    @classmethod
    def empty(
        cls,
        x_min: float,
        x_max: float,
        y_min: float,
        y_max: float,
        resolution: float = DEFAULT_RESOLUTION,
        value: int = UNKNOWN,
    ) -> OccupancyGrid:
        """A grid covering the axis-aligned rectangle, every cell set to `value`."""
        if not (x_min < x_max and y_min < y_max):
            raise GridError(
                f"need x_min < x_max and y_min < y_max, got {(x_min, x_max, y_min, y_max)}"
            )
        if not (math.isfinite(resolution) and resolution > 0):
            raise GridError(f"resolution must be > 0 metres per cell, got {resolution}")
        width = max(1, math.ceil((x_max - x_min) / resolution - 1e-9))
        height = max(1, math.ceil((y_max - y_min) / resolution - 1e-9))
        if width * height > MAX_CELLS:
            raise GridError(
                f"a {width} x {height} grid is more than {MAX_CELLS} cells; "
                "use a coarser resolution or a smaller area"
            )
        grid = cls(width, height, resolution, Pose2D(x_min, y_min, 0.0))
        grid.cells[:] = bytes([_byte(value)]) * (width * height)
        return grid

    @classmethod
    def from_msg(cls, msg: Mapping[str, Any]) -> OccupancyGrid:
        """Build from nav_msgs/OccupancyGrid as a dict (`info` and `data`, as the ROS edge gives
        it: info.width/height/resolution, info.origin.position.x/y and orientation z/w)."""
        try:
            info = msg["info"]
            data = msg["data"]
            pos = info["origin"]["position"]
            ori = info["origin"].get("orientation", {"z": 0.0, "w": 1.0})
            yaw = 2.0 * math.atan2(float(ori.get("z", 0.0)), float(ori.get("w", 1.0)))
            grid = cls(
                int(info["width"]),
                int(info["height"]),
                float(info["resolution"]),
                Pose2D(float(pos["x"]), float(pos["y"]), yaw),
            )
        except (KeyError, TypeError, AttributeError) as exc:
            raise GridError(f"not a nav_msgs/OccupancyGrid mapping: missing or bad {exc}") from exc
        grid.cells[:] = _cells_from_int8(data, grid.width * grid.height)
        return grid

    def to_msg(self) -> dict[str, Any]:
        """nav_msgs/OccupancyGrid as a dict (header left to the ROS edge)."""
        half = self.origin.yaw / 2.0
        return {
            "info": {
                "resolution": self.resolution,
                "width": self.width,
                "height": self.height,
                "origin": {
                    "position": {"x": self.origin.x, "y": self.origin.y, "z": 0.0},
                    "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(half), "w": math.cos(half)},
                },
            },
            "data": self.int8_data(),
        }

    def int8_data(self) -> list[int]:
        """The cells as int8 values (-1 unknown, 0..100), row-major."""
        return [v - 256 if v > 127 else v for v in self.cells]

    def copy(self) -> OccupancyGrid:
        return OccupancyGrid(
            self.width, self.height, self.resolution, self.origin, bytearray(self.cells)
        )

    # -- geometry ---------------------------------------------------------------------------

    def to_grid_frame(self, x: float, y: float) -> tuple[float, float]:
        """A point in the map frame as continuous cell coordinates (col, row) = cell corners
        at integers, so cell (c, r) spans [c, c+1) x [r, r+1)."""
        dx, dy = x - self.origin.x, y - self.origin.y
        gx = (dx * self._cos + dy * self._sin) / self.resolution
        gy = (-dx * self._sin + dy * self._cos) / self.resolution
        return gx, gy

    def cell_of(self, x: float, y: float) -> Cell:
        """The cell holding the point (it may lie outside the grid; see `contains`). Raises
        GridError for a point that is not finite numbers: no cell holds it."""
        bad = not_finite(x=x, y=y)
        if bad:
            raise GridError(f"no map cell holds a point that is not finite ({bad})")
        gx, gy = self.to_grid_frame(x, y)
        # A finite point far enough away overflows the grid frame (1e308 m): a cell _FAR
        # away is as far outside any map as the point's own would be.
        return Cell(math.floor(_within(gx, _FAR)), math.floor(_within(gy, _FAR)))

    def center_of(self, cell: Cell) -> tuple[float, float]:
        """The map-frame centre of a cell."""
        gx, gy = (cell.col + 0.5) * self.resolution, (cell.row + 0.5) * self.resolution
        return (
            self.origin.x + gx * self._cos - gy * self._sin,
            self.origin.y + gx * self._sin + gy * self._cos,
        )

    def contains(self, cell: Cell) -> bool:
        return 0 <= cell.col < self.width and 0 <= cell.row < self.height

    def index(self, cell: Cell) -> int:
        return cell.row * self.width + cell.col

    # -- cell values ------------------------------------------------------------------------

    def value(self, cell: Cell) -> int:
        """-1 unknown, 0..100 occupancy; cells outside the grid are unknown."""
        if not self.contains(cell):
            return UNKNOWN
        v = self.cells[self.index(cell)]
        return UNKNOWN if v == _UNKNOWN_BYTE else v

    def value_at(self, x: float, y: float) -> int:
        return self.value(self.cell_of(x, y))

    def set(self, cell: Cell, value: int) -> None:
        if not self.contains(cell):
            raise GridError(f"cell {cell} is outside the {self.width} x {self.height} grid")
        self.cells[self.index(cell)] = _byte(value)

    def is_occupied(self, cell: Cell) -> bool:
        v = self.value(cell)
        return v >= OCCUPIED_THRESHOLD

    def count(self, kind: str) -> int:
        """How many cells are `free`, `occupied` or `unknown`."""
        if kind == "unknown":
            return self.cells.count(_UNKNOWN_BYTE)
        occupied = sum(self.cells.count(v) for v in range(OCCUPIED_THRESHOLD, 101))
        if kind == "occupied":
            return occupied
        if kind == "free":
            return len(self.cells) - occupied - self.cells.count(_UNKNOWN_BYTE)
        raise GridError(f"kind must be free, occupied or unknown, got {kind!r}")

    # -- drawing known shapes ---------------------------------------------------------------

    def fill_rect(self, x_min: float, x_max: float, y_min: float, y_max: float, value: int) -> None:
        """Set every cell that overlaps the axis-aligned rectangle (origin yaw must be 0)."""
        self._require_axis_aligned()
        c0, r0 = self._floor_cell(x_min, y_min)
        c1, r1 = self._ceil_cell(x_max, y_max)
        c0, c1 = max(0, c0), min(self.width, c1)
        if c0 >= c1:
            return
        run = bytes([_byte(value)]) * (c1 - c0)
        for row in range(max(0, r0), min(self.height, r1)):
            base = row * self.width
            self.cells[base + c0 : base + c1] = run

    def fill_circle(self, x: float, y: float, radius: float, value: int) -> None:
        """Set every cell that overlaps the disc (conservative: a cell touched at all counts)."""
        self._require_axis_aligned()
        res = self.resolution
        gx, gy = (x - self.origin.x) / res, (y - self.origin.y) / res
        rad = radius / res
        for row in range(max(0, math.floor(gy - rad)), min(self.height, math.ceil(gy + rad))):
            # The widest chord of the disc inside this row's band [row, row + 1).
            dy = 0.0 if row <= gy <= row + 1 else min(abs(gy - row), abs(gy - row - 1))
            if dy > rad:
                continue
            half = math.sqrt(rad * rad - dy * dy)
            c0, c1 = max(0, math.floor(gx - half)), min(self.width, math.ceil(gx + half))
            if c0 < c1:
                base = row * self.width
                self.cells[base + c0 : base + c1] = bytes([_byte(value)]) * (c1 - c0)

    def _floor_cell(self, x: float, y: float) -> tuple[int, int]:
        gx, gy = self.to_grid_frame(x, y)
        return math.floor(gx + 1e-9), math.floor(gy + 1e-9)

    def _ceil_cell(self, x: float, y: float) -> tuple[int, int]:
        gx, gy = self.to_grid_frame(x, y)
        return math.ceil(gx - 1e-9), math.ceil(gy - 1e-9)

    def _require_axis_aligned(self) -> None:
        if self.origin.yaw != 0.0:
            raise GridError("drawing shapes needs a grid whose origin yaw is 0")


def _byte(value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not -1 <= value <= 100:
        raise GridError(f"cell values are -1 (unknown) or 0..100, got {value!r}")
    return _UNKNOWN_BYTE if value == UNKNOWN else value


def _cells_from_int8(data: Sequence[int] | bytes | Iterable[int], n: int) -> bytearray:
    if isinstance(data, (bytes, bytearray)):
        raw = bytearray(data)  # the int8 buffer as unsigned bytes: -1 is already 255
    else:
        try:
            raw = bytearray(v & 0xFF for v in data)
        except TypeError as exc:
            raise GridError(f"data must be integers -1..100, got {exc}") from exc
    if len(raw) != n:
        raise GridError(f"data has {len(raw)} cells, expected width * height = {n}")
    # Values outside -1..100 (other negatives) mean "unknown" to map_server's consumers too.
    bad = raw.translate(_VALID).find(0)
    if bad >= 0:
        raw = raw.translate(_NORMALISE)
    return raw


_VALID = bytes(1 if v <= 100 or v == _UNKNOWN_BYTE else 0 for v in range(256))
_NORMALISE = bytes(v if v <= 100 else _UNKNOWN_BYTE for v in range(256))


def _within(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))
