"""``python -m dronewrapper_compose`` runs a compose graph (the ``dronewrapper up`` command)."""

from dronewrapper_compose.up import main

if __name__ == "__main__":
    raise SystemExit(main())
