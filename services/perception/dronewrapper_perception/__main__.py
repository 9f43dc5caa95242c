"""perception: colour / YOLOX / HOG detection with target tracking, published as Detections."""

from dronewrapper.runtime.service import run_service
from dronewrapper_perception.config import Config
from dronewrapper_perception.node import PORTS, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_perception``)."""
    return run_service("perception", __doc__, Config, run, argv, ports=PORTS)


if __name__ == "__main__":
    raise SystemExit(main())
