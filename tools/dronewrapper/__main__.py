"""``python -m dronewrapper`` is the ``dronewrapper`` command."""

from dronewrapper.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
