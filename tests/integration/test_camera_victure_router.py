"""The camera_victure service on a real Zenoh router: the wiring (its logic runs on the fake bus
in tests/service/test_camera_victure_service.py)."""

from __future__ import annotations

from camera_running import VIDEO, Running

from dronewrapper.images import image_to_bgr
from support import wait_for


def test_publishes_stamped_bgr_frames_and_jpeg(router):
    """The moved stop-gap test: a real video file, raw and JPEG, like the simulator's, on a
    real router (the wiring; the other tests run on the fake bus)."""
    overrides = [f"source={VIDEO}", "jpeg=true"]
    with Running(overrides, router=router) as cam:
        wait_for(lambda: len(cam.raw) >= 5 and cam.jpeg.count >= 5, 20, what="frames")
        img = cam.raw[-1]
        assert img.encoding == "bgr8" and img.step == img.width * 3
        assert (img.width, img.height) == (768, 576)
        pixels = image_to_bgr(img)
        assert pixels.std() > 5  # a real picture, not a blank buffer
        assert img.header.stamp > 1e9 and img.header.frame_id == "cam_frontal"
        assert cam.jpeg.value.data[:2] == b"\xff\xd8"
        seqs = [m.header.seq for m in cam.raw]
        stamps = [m.header.stamp for m in cam.raw]
        assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)
        assert stamps == sorted(stamps)
        # at its own rate (10 fps): capture stamps 0.1 s apart on average (as fast as
        # possible would be a few ms; a loaded machine may stretch it, never shrink it)
        span = (stamps[-1] - stamps[0]) / (seqs[-1] - seqs[0])
        assert 0.08 < span < 0.3
    assert cam.result == [0]
