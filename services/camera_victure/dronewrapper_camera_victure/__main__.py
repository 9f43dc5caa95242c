"""camera_victure: a USB (V4L2) camera, video file, network stream or test pattern on Zenoh.

python -m dronewrapper_camera_victure --set source=/dev/video0 --set rotate=180
python -m dronewrapper_camera_victure --set source=video.avi --set jpeg=true
python -m dronewrapper_camera_victure --set source=rtsp://192.168.1.10:8554/cam
python -m dronewrapper_camera_victure --list
"""

import argparse

from dronewrapper.runtime.service import run_service
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.node import PORTS, run


def _add_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--list", action="store_true", help="list the V4L2 devices and their modes, then exit"
    )


def _configure(args: argparse.Namespace, _overrides: list[str]) -> None:
    if args.list:
        from dronewrapper_camera_victure.listing import list_devices

        raise SystemExit(list_devices())


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_camera_victure``)."""
    return run_service(
        "camera_victure",
        __doc__,
        Config,
        run,
        argv,
        add_args=_add_args,
        configure=_configure,
        ports=PORTS,
    )


if __name__ == "__main__":
    raise SystemExit(main())
