"""``python -m dronewrapper_sim``: the simulated aircraft (see dronewrapper_sim.cli)."""

from dronewrapper_sim.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
