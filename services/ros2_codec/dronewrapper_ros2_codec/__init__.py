"""ROS 2 on Zenoh (rmw_zenoh) without ROS 2: interface definitions, type hashes, CDR, names.

Pure modules, no I/O: :mod:`interfaces` (the ROS 2 message and service definitions the
MAVROS-equivalent keys map to, written here as ``.msg`` text), :mod:`typehash` (their RIHS01
hashes, REP-2011), :mod:`cdr` (the CDR payloads), :mod:`names` (rmw_zenoh key expressions and
liveliness tokens), :mod:`attachment` (the per-sample attachment), :mod:`convert` (our messages
to and from ROS 2 values), :mod:`mismatch` (type hash disagreements read from liveliness).
The ROS 2 gateway (``dronewrapper ros2``), the PX4 uXRCE/Zenoh bridge and the ROS 2 bag
writer use them; the laptop SDK does not ship them (services/ros2_codec/README.md).
"""
