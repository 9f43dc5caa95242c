"""The px4_msgs types this bridge reads and writes, as ``.msg`` field lists (constants and
comments left out: neither changes the wire format nor the RIHS01 hash).

The fields are those PX4's ``msg/`` directory defines at upstream main of 2026-03-02
(02e73e3b6f), the firmware the bridge was measured against: every type's RIHS01 hash equals the
one that firmware announces (tests/data/px4_zenoh holds its tokens and samples, and a test holds
our definitions to them). A firmware whose messages differ announces other hashes, and
:mod:`.versions` refuses them.
Units and frames are PX4's: metres, m/s, radians, NED local frame, FRD body frame,
microseconds since the autopilot's boot for ``timestamp``.
"""

from __future__ import annotations

from dronewrapper_ros2_codec import interfaces

PACKAGE = "px4_msgs"

FIELDS: dict[str, str] = {
    "VehicleStatus": (
        "uint64 timestamp\nuint64 armed_time\nuint64 takeoff_time\nuint8 arming_state\n"
        "uint8 latest_arming_reason\nuint8 latest_disarming_reason\nuint64 nav_state_timestamp\n"
        "uint8 nav_state_user_intention\nuint8 nav_state\nuint8 executor_in_charge\n"
        "uint8 nav_state_display\nuint32 valid_nav_states_mask\nuint32 can_set_nav_states_mask\n"
        "uint16 failure_detector_status\nuint8 hil_state\nuint8 vehicle_type\nbool failsafe\n"
        "bool failsafe_and_user_took_over\nuint8 failsafe_defer_state\n"
        "bool gcs_connection_lost\nuint8 gcs_connection_lost_counter\n"
        "bool high_latency_data_link_lost\nbool is_vtol\nbool is_vtol_tailsitter\n"
        "bool in_transition_mode\nbool in_transition_to_fw\nuint8 system_type\nuint8 system_id\n"
        "uint8 component_id\nbool safety_button_available\nbool safety_off\n"
        "bool power_input_valid\nbool usb_connected\nbool open_drone_id_system_present\n"
        "bool open_drone_id_system_healthy\nbool parachute_system_present\n"
        "bool parachute_system_healthy\nbool traffic_avoidance_system_present\n"
        "bool rc_calibration_in_progress\nbool calibration_enabled\nbool pre_flight_checks_pass\n"
    ),
    "VehicleLocalPosition": (
        "uint64 timestamp\nuint64 timestamp_sample\nbool xy_valid\nbool z_valid\nbool v_xy_valid\n"
        "bool v_z_valid\nfloat32 x\nfloat32 y\nfloat32 z\nfloat32[2] delta_xy\n"
        "uint8 xy_reset_counter\nfloat32 delta_z\nuint8 z_reset_counter\nfloat32 vx\nfloat32 vy\n"
        "float32 vz\nfloat32 z_deriv\nfloat32[2] delta_vxy\nuint8 vxy_reset_counter\n"
        "float32 delta_vz\nuint8 vz_reset_counter\nfloat32 ax\nfloat32 ay\nfloat32 az\n"
        "float32 heading\nfloat32 heading_var\nfloat32 unaided_heading\nfloat32 delta_heading\n"
        "uint8 heading_reset_counter\nbool heading_good_for_control\nfloat32 tilt_var\n"
        "bool xy_global\nbool z_global\nuint64 ref_timestamp\nfloat64 ref_lat\nfloat64 ref_lon\n"
        "float32 ref_alt\nbool dist_bottom_valid\nfloat32 dist_bottom\nfloat32 dist_bottom_var\n"
        "float32 delta_dist_bottom\nuint8 dist_bottom_reset_counter\n"
        "uint8 dist_bottom_sensor_bitfield\nfloat32 eph\nfloat32 epv\nfloat32 evh\nfloat32 evv\n"
        "bool dead_reckoning\nfloat32 vxy_max\nfloat32 vz_max\nfloat32 hagl_min\n"
        "float32 hagl_max_z\nfloat32 hagl_max_xy\n"
    ),
    "VehicleAttitude": (
        "uint64 timestamp\nuint64 timestamp_sample\nfloat32[4] q\nfloat32[4] delta_q_reset\n"
        "uint8 quat_reset_counter\n"
    ),
    "VehicleGlobalPosition": (
        "uint64 timestamp\nuint64 timestamp_sample\nfloat64 lat\nfloat64 lon\nfloat32 alt\n"
        "float32 alt_ellipsoid\nbool lat_lon_valid\nbool alt_valid\nfloat32 delta_alt\n"
        "float32 delta_terrain\nuint8 lat_lon_reset_counter\nuint8 alt_reset_counter\n"
        "uint8 terrain_reset_counter\nfloat32 eph\nfloat32 epv\nfloat32 terrain_alt\n"
        "bool terrain_alt_valid\nbool dead_reckoning\n"
    ),
    "BatteryStatus": (
        "uint64 timestamp\nbool connected\nfloat32 voltage_v\nfloat32 current_a\n"
        "float32 current_average_a\nfloat32 discharged_mah\nfloat32 remaining\nfloat32 scale\n"
        "float32 time_remaining_s\nfloat32 temperature\nuint8 cell_count\nuint8 source\n"
        "uint8 priority\nuint16 capacity\nuint16 cycle_count\nuint16 average_time_to_empty\n"
        "uint16 manufacture_date\nuint16 state_of_health\nuint16 max_error\nuint8 id\n"
        "uint16 interface_error\nfloat32[14] voltage_cell_v\nfloat32 max_cell_voltage_delta\n"
        "bool is_powering_off\nbool is_required\nuint8 warning\nuint16 faults\n"
        "float32 full_charge_capacity_wh\nfloat32 remaining_capacity_wh\n"
        "uint16 over_discharge_count\nfloat32 nominal_voltage\n"
        "float32 internal_resistance_estimate\nfloat32 ocv_estimate\n"
        "float32 ocv_estimate_filtered\nfloat32 volt_based_soc_estimate\n"
        "float32 voltage_prediction\nfloat32 prediction_error\n"
        "float32 estimation_covariance_norm\n"
    ),
    "VehicleLandDetected": (
        "uint64 timestamp\nbool freefall\nbool ground_contact\nbool maybe_landed\nbool landed\n"
        "bool in_ground_effect\nbool in_descend\nbool has_low_throttle\nbool vertical_movement\n"
        "bool horizontal_movement\nbool rotational_movement\n"
        "bool close_to_ground_or_skipped_check\nbool at_rest\n"
    ),
    "VehicleCommand": (
        "uint64 timestamp\nfloat32 param1\nfloat32 param2\nfloat32 param3\nfloat32 param4\n"
        "float64 param5\nfloat64 param6\nfloat32 param7\nuint32 command\nuint8 target_system\n"
        "uint8 target_component\nuint8 source_system\nuint16 source_component\n"
        "uint8 confirmation\nbool from_external\n"
    ),
    "VehicleCommandAck": (
        "uint64 timestamp\nuint32 command\nuint8 result\nuint8 result_param1\n"
        "int32 result_param2\nuint8 target_system\nuint16 target_component\nbool from_external\n"
    ),
    "OffboardControlMode": (
        "uint64 timestamp\nbool position\nbool velocity\nbool acceleration\nbool attitude\n"
        "bool body_rate\nbool thrust_and_torque\nbool direct_actuator\n"
    ),
    "TrajectorySetpoint": (
        "uint64 timestamp\nfloat32[3] position\nfloat32[3] velocity\nfloat32[3] acceleration\n"
        "float32[3] jerk\nfloat32 yaw\nfloat32 yawspeed\n"
    ),
}
"""Each type's fields, by short name (``VehicleStatus`` is ``px4_msgs/msg/VehicleStatus``)."""


def full_name(short: str) -> str:
    """``VehicleStatus`` -> ``px4_msgs/msg/VehicleStatus``."""
    return f"{PACKAGE}/msg/{short}"


interfaces.define({full_name(short): text for short, text in FIELDS.items()})
