"""bridge_tello: a DJI Tello (Tello SDK 2.0 over UDP) on the MAVROS-equivalent Zenoh keys.

Import name ``dronewrapper_bridge_tello``; run ``python -m dronewrapper_bridge_tello``.
"""
