"""What a capture leaves out: a camera's own JPEG once its raw frames are stored as JPEG, and
an argument that the shell expanded into a path is warned about (pure)."""

from __future__ import annotations

from dronewrapper.echo import path_warning
from dronewrapper.record.capture import OneStreamPerCamera

RAW, JPEG = "drone/cam_frontal/image_raw", "drone/cam_frontal/image_raw/compressed"


def test_with_jpeg_storage_a_camera_is_stored_once():
    once = OneStreamPerCamera(enabled=True)
    assert once.keep(JPEG)  # no raw frame yet: the camera's JPEG is all there is
    assert once.keep(RAW)
    assert not once.keep(JPEG)  # from now on the raw frame, as JPEG, is the one copy
    assert once.keep("drone/cam_ventral/image_raw/compressed")  # another camera
    assert once.keep("drone/mavros/state")


def test_without_jpeg_storage_everything_is_kept():
    once = OneStreamPerCamera(enabled=False)
    assert once.keep(RAW) and once.keep(JPEG)


def test_an_argument_that_is_a_path_here_is_warned_about():
    here = {"sim/README.md", "sim"}
    warning = path_warning("sim/README.md", exists=here.__contains__)
    assert warning is not None and "unquoted" in warning and "'sim/**'" in warning
    assert path_warning("sim/**", exists=here.__contains__) is None
