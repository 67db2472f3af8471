"""The simulator's world and its camera (scene.py, renderer.py): sightings, occlusion, the raycast
image and its PNG."""

from __future__ import annotations

import math
import struct
import zlib

import pytest

from shadowhound.robot.sim.renderer import camera_frame, encode_png, render
from shadowhound.robot.sim.scene import DEFAULT_WORLD, World, WorldObject, visible_objects
from shadowhound.state import Pose2D

W, H = 160, 120
RED = (220, 40, 40)


def decode_png(data: bytes) -> tuple[int, int, bytes]:
    """Just enough PNG reading to check ours: 8-bit RGB, unfiltered scanlines, CRCs checked."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width, height = 8, b"", 0, 0
    kinds = []
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        payload = data[pos + 8 : pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])
        assert crc == zlib.crc32(kind + payload) & 0xFFFFFFFF, kind
        kinds.append(kind)
        if kind == b"IHDR":
            width, height, depth, colour_type, _, _, interlace = struct.unpack(">IIBBBBB", payload)
            assert (depth, colour_type, interlace) == (8, 2, 0)
        elif kind == b"IDAT":
            idat += payload
        pos += 12 + length
    assert kinds[0] == b"IHDR" and kinds[-1] == b"IEND"
    raw = zlib.decompress(idat)
    stride = width * 3
    assert len(raw) == height * (stride + 1)
    rows = []
    for r in range(height):
        line = raw[r * (stride + 1) : (r + 1) * (stride + 1)]
        assert line[0] == 0, "decoder only handles filter type 0"
        rows.append(line[1:])
    return width, height, b"".join(rows)


def pixel(rgb: bytes, width: int, x: int, y: int) -> tuple[int, int, int]:
    i = (y * width + x) * 3
    return rgb[i], rgb[i + 1], rgb[i + 2]


def red_dominant(p: tuple[int, int, int]) -> bool:
    r, g, b = p
    return r > 2 * g and r > 2 * b and r > 60


def red_rows(rgb: bytes, width: int, height: int) -> int:
    """How many rows of the centre column show the red ball."""
    return sum(red_dominant(pixel(rgb, width, width // 2, y)) for y in range(height))


def names(sightings: tuple) -> list[str]:
    return [s.name for s in sightings]


def test_object_straight_ahead_is_seen_at_its_distance() -> None:
    seen = {s.name: s for s in visible_objects(DEFAULT_WORLD, Pose2D(0.0, 0.0, 0.0))}
    ball = seen["red ball"]
    assert ball.bearing_deg == pytest.approx(0.0, abs=1e-6)
    assert ball.distance == pytest.approx(3.0)
    assert "ahead" in ball.describe()


def test_turning_around_loses_the_object_ahead() -> None:
    behind = visible_objects(DEFAULT_WORLD, Pose2D(0.0, 0.0, math.pi))
    assert "red ball" not in names(behind)
    assert names(behind) == ["charging dock"]  # at (-3, -1): facing -x, -y is to the left
    assert behind[0].bearing_deg == pytest.approx(math.degrees(math.atan2(1.0, 3.0)))


def test_bearing_sign_left_positive_right_negative() -> None:
    seen = {s.name: s for s in visible_objects(DEFAULT_WORLD, Pose2D())}
    assert seen["blue box"].bearing_deg == pytest.approx(math.degrees(math.atan2(2.0, 2.5)))
    assert seen["green plant"].bearing_deg < 0
    assert "person" not in seen  # 69 degrees to the right: outside a 90 degree field of view


def test_bearing_follows_pose_and_yaw() -> None:
    world = World(objects=(WorldObject("cone", 2.0, 3.0),))
    (s,) = visible_objects(world, Pose2D(2.0, 1.0, math.pi / 2))
    assert s.bearing_deg == pytest.approx(0.0, abs=1e-6)
    assert s.distance == pytest.approx(2.0)
    (s,) = visible_objects(world, Pose2D(2.0, 1.0, math.radians(60)))
    assert s.bearing_deg == pytest.approx(30.0)


def test_sightings_are_sorted_nearest_first_and_limited_by_range() -> None:
    sightings = visible_objects(DEFAULT_WORLD, Pose2D())
    distances = [s.distance for s in sightings]
    assert distances == sorted(distances)
    assert names(visible_objects(DEFAULT_WORLD, Pose2D(), max_range=3.1)) == ["red ball"]
    assert visible_objects(DEFAULT_WORLD, Pose2D(), fov_deg=10.0)[0].name == "red ball"


def test_tall_nearer_object_hides_the_one_behind() -> None:
    world = World(
        objects=(
            WorldObject("red ball", 3.0, 0.0, radius=0.2, height=0.4, color=RED),
            WorldObject("crate", 1.5, 0.0, radius=0.5, height=1.0, color=(90, 60, 30)),
        )
    )
    assert names(visible_objects(world, Pose2D())) == ["crate"]
    # Step sideways so the crate no longer covers the ball.
    assert "red ball" in names(visible_objects(world, Pose2D(0.0, 1.5, 0.0)))
    rgb = render(world, Pose2D(), W, H)
    assert red_rows(rgb, W, H) == 0


def test_short_nearer_object_does_not_hide_a_taller_one() -> None:
    world = World(
        objects=(
            WorldObject("red ball", 2.0, 0.0, radius=0.3, height=0.4, color=RED),
            WorldObject("person", 4.0, 0.0, radius=0.25, height=1.7, color=(140, 70, 170)),
        )
    )
    assert names(visible_objects(world, Pose2D())) == ["red ball", "person"]


def test_partly_covered_object_is_still_seen() -> None:
    world = World(
        objects=(
            WorldObject("wide", 4.0, 0.0, radius=0.6, height=1.0),
            WorldObject("post", 2.0, 0.0, radius=0.1, height=2.0),
        )
    )
    assert names(visible_objects(world, Pose2D())) == ["post", "wide"]


def test_objects_outside_the_room_are_not_seen() -> None:
    world = World(objects=(WorldObject("outside", 8.0, 0.0),), bounds=(-6.0, 6.0, -6.0, 6.0))
    assert visible_objects(world, Pose2D(), max_range=20.0) == ()


def test_render_size_and_ahead_object_colour_in_png() -> None:
    frame = camera_frame(DEFAULT_WORLD, Pose2D(), W, H, stamp=12.5)
    assert (frame.encoding, frame.source, frame.stamp) == ("png", "simulator", 12.5)
    assert frame.sightings == visible_objects(DEFAULT_WORLD, Pose2D())
    width, height, rgb = decode_png(frame.data)
    assert (width, height) == (W, H) == (frame.width, frame.height)
    assert rgb == render(DEFAULT_WORLD, Pose2D(), W, H)
    # The ball (0.4 m tall, 3 m away) straddles the horizon in the middle of the image.
    for y in range(H // 2 - 2, H // 2 + 7):
        assert red_dominant(pixel(rgb, W, W // 2, y)), y
    # Above it is wall, below it floor: neither is red.
    assert not red_dominant(pixel(rgb, W, W // 2, H // 4))
    assert not red_dominant(pixel(rgb, W, W // 2, H - 1))


def test_turned_around_the_centre_shows_no_red() -> None:
    rgb = render(DEFAULT_WORLD, Pose2D(0.0, 0.0, math.pi), W, H)
    assert len(rgb) == W * H * 3
    assert red_rows(rgb, W, H) == 0


def test_nearer_objects_span_more_rows() -> None:
    spans = [
        red_rows(render(DEFAULT_WORLD, Pose2D(x, 0.0, 0.0), W, H), W, H)
        for x in (-1.5, 0.0, 1.5, 2.2)  # 4.5, 3, 1.5 and 0.8 m from the ball
    ]
    assert spans[0] > 0
    assert spans == sorted(spans) and len(set(spans)) == len(spans), spans


def test_taller_objects_look_taller() -> None:
    def rows(height: float) -> int:
        world = World(objects=(WorldObject("thing", 3.0, 0.0, 0.3, height, RED),))
        return red_rows(render(world, Pose2D(), W, H), W, H)

    assert rows(0.3) < rows(0.8) < rows(1.7)


def test_render_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError):
        render(DEFAULT_WORLD, Pose2D(), 0, H)
    with pytest.raises(ValueError):
        render(DEFAULT_WORLD, Pose2D(), W, H, fov_deg=180.0)


def test_encode_png_validates_length() -> None:
    with pytest.raises(ValueError, match="expected 12"):
        encode_png(b"\x00" * 11, 2, 2)
    width, height, rgb = decode_png(encode_png(bytes(range(12)), 2, 2))
    assert (width, height, rgb) == (2, 2, bytes(range(12)))


def test_camera_outside_the_room_does_not_crash() -> None:
    rgb = render(DEFAULT_WORLD, Pose2D(-10.0, 0.0, 0.0), W, H)
    assert len(rgb) == W * H * 3
    assert visible_objects(DEFAULT_WORLD, Pose2D(-10.0, 0.0, 0.0), max_range=20.0) == ()


def test_world_dict_round_trip() -> None:
    assert World.from_dict(DEFAULT_WORLD.to_dict()) == DEFAULT_WORLD
    world = World.from_dict(
        {"half_size": 4, "objects": [{"name": "cone", "x": 1, "y": -1, "color": [255, 128, 0]}]}
    )
    assert world.bounds == (-4.0, 4.0, -4.0, 4.0)
    assert world.find("CONE") == WorldObject("cone", 1.0, -1.0, color=(255, 128, 0))
    assert World.from_dict({}) == World()


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"objects": [{"name": "a", "x": 1, "y": 0, "radius": "big"}]}, "objects[0].radius"),
        ({"objects": [{"name": "a", "x": 1, "y": 0}, {"x": 1, "y": 2}]}, "objects[1].name"),
        ({"objects": [{"name": "a", "x": True, "y": 0}]}, "objects[0].x"),
        ({"objects": [{"name": "a", "x": 1, "y": 0, "height": -1}]}, "objects[0].height"),
        ({"objects": [{"name": "a", "x": 1, "y": 0, "color": [300, 0, 0]}]}, "objects[0].color"),
        ({"objects": [{"name": "a", "x": 1, "y": 0, "radious": 1}]}, "radious"),
        ({"objects": [{"name": "a", "x": 1, "y": 0}, {"name": "A", "x": 2, "y": 0}]}, "duplicate"),
        ({"objects": {"name": "a"}}, "objects"),
        ({"objects": ["ball"]}, "objects[0]"),
        ({"bounds": [1, 0, 0, 1]}, "bounds"),
        ({"bounds": [0, 1, 0]}, "bounds"),
        ({"half_size": float("nan")}, "half_size"),
        ({"wall_color": "grey"}, "wall_color"),
        ({"wall_height": 0}, "wall_height"),
        ({"colour": [1, 2, 3]}, "colour"),
        ("not a dict", "world"),
    ],
)
def test_bad_world_dict_names_the_field(data: object, field: str) -> None:
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        World.from_dict(data)  # type: ignore[arg-type]
