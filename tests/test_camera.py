import pytest

from shadowhound.camera import image_size, raw_image_frame, to_camera_frame
from shadowhound.robot.sim.renderer import encode_png, render
from shadowhound.robot.sim.scene import DEFAULT_WORLD
from shadowhound.state import CameraFrame, Pose2D
from tests.images import tiny_jpeg


def test_jpeg_and_png_sizes():
    assert image_size(tiny_jpeg(640, 480)) == ("jpeg", 640, 480)
    png = encode_png(render(DEFAULT_WORLD, Pose2D(), 32, 24), 32, 24)
    assert image_size(png) == ("png", 32, 24)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "empty"),
        (b"GIF89a....", "JPEG or PNG"),
        (b"\xff\xd8\xff", "truncated"),
        (b"\x89PNG\r\n\x1a\n", "truncated"),
        (12, "unsupported camera frame int"),
    ],
)
def test_bad_frames_are_rejected_clearly(data, message):
    with pytest.raises(ValueError, match=message):
        to_camera_frame(data)


def test_arrays_become_raw_frames():
    class Array:  # the numpy surface the converter relies on
        def __init__(self, shape):
            self.shape, self.dtype = shape, "uint8"

        def tobytes(self):
            n = 1
            for d in self.shape:
                n *= d
            return bytes(n)

    frame = to_camera_frame(Array((48, 64, 3)))
    assert (frame.width, frame.height, frame.encoding) == (64, 48, "rgb8")
    assert to_camera_frame(Array((4, 5))).encoding == "mono8"
    with pytest.raises(ValueError, match="HxWx3"):
        to_camera_frame(Array((4, 5, 4)))


def test_frames_pass_through():
    frame = CameraFrame(b"x", 1, 1, "mono8")
    assert to_camera_frame(frame) is frame


def test_encode_jpeg_converts_and_downscales():
    pytest.importorskip("PIL")
    from shadowhound.camera import encode_jpeg

    png = encode_png(render(DEFAULT_WORLD, Pose2D(), 160, 120), 160, 120)
    frame = to_camera_frame(png)
    jpeg = encode_jpeg(frame, max_side=64)
    assert image_size(jpeg) == ("jpeg", 64, 48)
    raw = CameraFrame(bytes(range(12)) * 4, 4, 4, "bgr8")
    assert image_size(encode_jpeg(raw)) == ("jpeg", 4, 4)
    same = to_camera_frame(jpeg)
    assert encode_jpeg(same) is same.data  # a JPEG that fits is passed through
    with pytest.raises(ValueError, match="could not be decoded"):
        encode_jpeg(CameraFrame(b"\x89PNG\r\n\x1a\nbroken", 4, 4, "png"))


# -- raw sensor_msgs/Image fields (the ROS node and the Go2 robot) --------------------------


def test_raw_frame_row_padding_is_removed() -> None:
    rows = [bytes([r]) * 6 + b"\xee\xee" for r in range(3)]  # 2 px rgb8 + 2 bytes padding
    frame = raw_image_frame(b"".join(rows), 2, 3, "rgb8", 8)
    assert (frame.width, frame.height, frame.encoding) == (2, 3, "rgb8")
    assert frame.data == b"\x00" * 6 + b"\x01" * 6 + b"\x02" * 6


def test_raw_frame_without_padding_keeps_its_bytes() -> None:
    frame = raw_image_frame(bytearray(range(12)), 4, 3, "mono8", 4)
    assert frame.data == bytes(range(12)) and frame.encoding == "mono8"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((b"\0" * 12, 2, 2, "yuv422", 6), "unsupported image encoding 'yuv422'"),
        ((b"\0" * 12, 2, 2, "rgb8", 5), "step 5 is smaller than a rgb8 row"),
        ((b"\0" * 11, 2, 2, "rgb8", 6), "image data has 11 bytes"),
        ((b"", 0, 0, "mono8", 0), "image size 0x0 is out of range"),
    ],
)
def test_bad_raw_frames_are_refused(args: tuple, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        raw_image_frame(*args)
