"""Web ground station: ``python -m dronewrapper_ground_station`` = ``dronewrapper station``."""

from dronewrapper_ground_station.cli import main

raise SystemExit(main())
