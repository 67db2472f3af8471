import pytest

from shadowhound.camera import image_size, to_camera_frame
from shadowhound.robot.scene import DEFAULT_WORLD, encode_png, render
from shadowhound.state import CameraFrame, Pose2D
from tests.images import tiny_jpeg


def test_jpeg_and_png_sizes():
    assert image_size(tiny_jpeg(640, 480)) == ("jpeg", 640, 480)
    png = encode_png(render(DEFAULT_WORLD, Pose2D(), 32, 24), 32, 24)
    assert image_size(png) == ("png", 32, 24)


@pytest.mark.parametrize(("data", "message"), [
    (b"", "empty"), (b"GIF89a....", "JPEG or PNG"), (b"\xff\xd8\xff", "truncated"),
    (b"\x89PNG\r\n\x1a\n", "truncated"), (12, "unsupported camera frame int"),
])
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
