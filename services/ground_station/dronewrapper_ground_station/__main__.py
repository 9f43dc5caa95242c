"""Web ground station: ``python -m dronewrapper_ground_station`` = ``dronewrapper station``."""

from dronewrapper_ground_station.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
