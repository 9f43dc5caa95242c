"""The simulated world: scenarios (YAML), objects and their motion. Pure: no I/O but reading
scenario files, no clock."""
