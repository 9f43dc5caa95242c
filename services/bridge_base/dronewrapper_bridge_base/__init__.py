"""What every bridge process shares and no laptop needs: the pure core's base and the driver that
feeds it (``core_driver``), the operations a service call runs to its end (``operation``), the
commander lease (``commander_lease``), the setpoint watchdog of the failsafe
(``setpoint_watchdog``) and the node every bridge stands on (``bridge_node``)."""
