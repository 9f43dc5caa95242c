"""perception: colour / YOLOX / HOG detection with target tracking, published as Detections."""

from dronewrapper.runtime.service import run_service
from dronewrapper_perception.config import Config
from dronewrapper_perception.node import run

if __name__ == "__main__":
    raise SystemExit(run_service("perception", __doc__, Config, run))
