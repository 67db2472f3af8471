"""The simulated camera's picture of the world (`scene.py`): a raycast RGB image and its PNG.

`render` is a per-column raycaster in the style of Wolfenstein 3D, written with the standard
library only so the core package stays light. It casts the same rays as the scene's
`visible_objects`, so a `camera_frame`'s picture and its ground-truth sightings agree.
"""

from __future__ import annotations

import math
import struct
import time
import zlib
from functools import lru_cache

from ...state import CameraFrame, Pose2D
from .scene import CAMERA_HEIGHT, RAY_EPS, Color, World, ray_box, visible_objects

DISTANCE_FALLOFF = 0.12  # brightness = 1 / (1 + falloff * metres): a cheap depth cue


def _shade(color: Color, factor: float) -> bytes:
    r, g, b = color
    return bytes((min(255, int(r * factor)), min(255, int(g * factor)), min(255, int(b * factor))))


@lru_cache(maxsize=16)
def _column_rays(width: int, fov_deg: float) -> tuple[float, tuple[tuple[float, float], ...]]:
    """Focal length in pixels and, per column, (angle offset from the view axis, its cosine)."""
    focal = (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
    centre = width / 2.0
    rays = []
    for i in range(width):
        offset = math.atan((centre - (i + 0.5)) / focal)
        rays.append((offset, math.cos(offset)))
    return focal, tuple(rays)


@lru_cache(maxsize=16)
def _background(
    height: int, focal: float, wall_height: float, floor: Color, ceiling: Color
) -> bytes:
    """One image column of ceiling above the horizon and floor below, darkening toward it.

    With a level pinhole camera every pixel in an image row sees the floor (or ceiling) at the
    same perpendicular distance, so the shading is per row and one column serves them all.
    """
    horizon = height / 2.0
    parts = []
    for row in range(height):
        v = row + 0.5 - horizon
        if v > 0:
            depth = focal * CAMERA_HEIGHT / v
            parts.append(_shade(floor, 1.0 / (1.0 + DISTANCE_FALLOFF * depth)))
        else:
            depth = focal * (wall_height - CAMERA_HEIGHT) / max(-v, 0.5)
            parts.append(_shade(ceiling, 1.0 / (1.0 + DISTANCE_FALLOFF * depth)))
    return b"".join(parts)


def render(
    world: World, pose: Pose2D, width: int = 160, height: int = 120, fov_deg: float = 90.0
) -> bytes:
    """A first-person RGB8 image (row-major, 3 bytes per pixel) from a camera at `pose`.

    Each column casts one ray; the walls and every cylinder it meets are drawn far to near as
    vertical spans projected by a level pinhole camera CAMERA_HEIGHT above the floor, so a short
    object in front of a tall one hides only its lower part.
    """
    if width <= 0 or height <= 0:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    if not 0.0 < fov_deg < 180.0:
        raise ValueError(f"fov_deg must be in (0, 180), got {fov_deg}")
    focal, rays = _column_rays(width, float(fov_deg))
    horizon = height / 2.0
    background = _background(
        height, focal, world.wall_height, world.floor_color, world.ceiling_color
    )
    wall_rise = world.wall_height - CAMERA_HEIGHT
    ox, oy, yaw = pose.x, pose.y, pose.yaw
    bounds = world.bounds
    # Per-object terms that do not depend on the ray, hoisted out of the column loop.
    objs = [
        (
            o,
            o.x - ox,
            o.y - oy,
            (o.x - ox) ** 2 + (o.y - oy) ** 2 - o.radius**2,
            o.height - CAMERA_HEIGHT,
        )
        for o in world.objects
    ]
    stride = width * 3
    image = bytearray(stride * height)
    for i, (offset, cos_offset) in enumerate(rays):
        angle = yaw + offset
        dx = math.cos(angle)
        dy = math.sin(angle)
        column = bytearray(background)
        # Wolfenstein-style side shading: x-walls and y-walls differ, so corners read clearly.
        t_wall, x_side = ray_box(ox, oy, dx, dy, bounds)
        hits: list[tuple[float, bytes, float]] = []
        if t_wall < math.inf:
            light = (1.0 if x_side else 0.8) / (1.0 + DISTANCE_FALLOFF * t_wall)
            hits.append((t_wall, _shade(world.wall_color, light), wall_rise))
        for obj, lx, ly, c, rise in objs:
            tca = lx * dx + ly * dy
            if tca <= 0.0:
                continue
            disc = tca * tca - c  # r^2 - (squared distance from the centre to the ray)
            if disc < 0.0:
                continue
            t = tca - math.sqrt(disc)
            if t <= RAY_EPS or t >= t_wall:
                continue
            # Lambert-like term from the surface normal so cylinders look round, not flat.
            facing = (tca - t) / obj.radius
            light = (0.55 + 0.45 * facing) / (1.0 + DISTANCE_FALLOFF * t)
            hits.append((t, _shade(obj.color, light), rise))
        hits.sort(key=lambda h: -h[0])
        for t, pixel, rise in hits:
            depth = max(t * cos_offset, 1e-3)  # perpendicular depth: no fisheye bulge
            top = max(0, int(horizon - focal * rise / depth + 0.5))
            bottom = min(height, int(horizon + focal * CAMERA_HEIGHT / depth + 0.5))
            if bottom > top:
                column[top * 3 : bottom * 3] = pixel * (bottom - top)
        # Scatter the column into the row-major image one channel at a time: three extended
        # slice assignments in C instead of `height` Python-level pixel copies.
        base = i * 3
        image[base::stride] = column[0::3]
        image[base + 1 :: stride] = column[1::3]
        image[base + 2 :: stride] = column[2::3]
    return bytes(image)


def encode_png(rgb: bytes, width: int, height: int) -> bytes:
    """Encode RGB8 pixels (row-major) as an 8-bit truecolour PNG."""
    if width <= 0 or height <= 0:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    if len(rgb) != width * height * 3:
        raise ValueError(
            f"rgb has {len(rgb)} bytes, expected {width * height * 3} for {width}x{height} RGB8"
        )
    stride = width * 3
    # Filter type 0 (None) on every scanline: simple, and zlib copes well with flat colour spans.
    raw = b"".join(b"\x00" + rgb[r * stride : (r + 1) * stride] for r in range(height))

    def chunk(kind: bytes, payload: bytes) -> bytes:
        return (
            struct.pack(">I", len(payload))
            + kind
            + payload
            + struct.pack(">I", zlib.crc32(kind + payload) & 0xFFFFFFFF)
        )

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 6))
        + chunk(b"IEND", b"")
    )


def camera_frame(
    world: World,
    pose: Pose2D,
    width: int = 160,
    height: int = 120,
    fov_deg: float = 90.0,
    stamp: float | None = None,
    max_range: float = 10.0,
) -> CameraFrame:
    """A simulated camera frame: the rendered PNG plus ground-truth sightings.

    `stamp` defaults to the current wall-clock time, matching CameraFrame's own default.
    """
    rgb = render(world, pose, width, height, fov_deg)
    return CameraFrame(
        data=encode_png(rgb, width, height),
        width=width,
        height=height,
        encoding="png",
        stamp=time.time() if stamp is None else stamp,
        source="simulator",
        sightings=visible_objects(world, pose, fov_deg, max_range),
    )


__all__ = ["DISTANCE_FALLOFF", "camera_frame", "encode_png", "render"]
