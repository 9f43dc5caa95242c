"""``python -m dronewrapper`` is the ``dronewrapper`` command."""

from dronewrapper.cli import main

raise SystemExit(main())
