"""ROS 2 gateway: a drone's MAVROS-equivalent keys as ROS 2 topics and services over rmw_zenoh.

Pure parts: :mod:`config`, :mod:`entities` (which key is which ROS 2 entity). The process:
:mod:`node` (run as ``python -m dronewrapper_ros2_gateway`` or ``dronewrapper ros2``).
"""
