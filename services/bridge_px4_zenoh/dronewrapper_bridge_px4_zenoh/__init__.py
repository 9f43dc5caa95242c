"""The PX4 Zenoh bridge: PX4's own ``zenoh`` module (uORB topics in rmw_zenoh's wire format) as
the MAVROS-equivalent keys the other bridges present, with no MAVLink in between."""
