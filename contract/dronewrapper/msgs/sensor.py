"""Sensor messages shaped like ROS sensor_msgs: GNSS fix, battery, images."""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header

# sensor_msgs/NavSatStatus.status
NAVSAT_STATUS_NO_FIX = -1
NAVSAT_STATUS_FIX = 0
NAVSAT_STATUS_SBAS_FIX = 1
NAVSAT_STATUS_GBAS_FIX = 2

# sensor_msgs/NavSatFix.position_covariance_type
COVARIANCE_TYPE_UNKNOWN = 0
COVARIANCE_TYPE_APPROXIMATED = 1
COVARIANCE_TYPE_DIAGONAL_KNOWN = 2
COVARIANCE_TYPE_KNOWN = 3

# sensor_msgs/BatteryState.power_supply_status
POWER_SUPPLY_STATUS_UNKNOWN = 0
POWER_SUPPLY_STATUS_CHARGING = 1
POWER_SUPPLY_STATUS_DISCHARGING = 2


class NavSatStatus(msgspec.Struct, frozen=True, kw_only=True):
    """GNSS fix status (``status`` is one of the NAVSAT_STATUS_* constants)."""

    status: int = NAVSAT_STATUS_NO_FIX
    service: int = 1  # SERVICE_GPS


class NavSatFix(msgspec.Struct, frozen=True, kw_only=True):
    """Global position: WGS-84 latitude/longitude in degrees, altitude in metres (AMSL)."""

    header: Header = msgspec.field(default_factory=Header)
    status: NavSatStatus = msgspec.field(default_factory=NavSatStatus)
    latitude: float = 0.0
    longitude: float = 0.0
    altitude: float = 0.0
    position_covariance: list[float] = msgspec.field(default_factory=lambda: [0.0] * 9)
    position_covariance_type: int = COVARIANCE_TYPE_UNKNOWN


class BatteryState(msgspec.Struct, kw_only=True, frozen=True):
    """Battery state. ``percentage`` is a fraction 0..1 on every aircraft (NaN if unknown)."""

    header: Header = msgspec.field(default_factory=Header)
    voltage: float = float("nan")
    current: float = float("nan")
    charge: float = float("nan")
    capacity: float = float("nan")
    percentage: float = float("nan")
    power_supply_status: int = POWER_SUPPLY_STATUS_UNKNOWN
    present: bool = True


class Image(msgspec.Struct, kw_only=True, frozen=True):
    """An uncompressed image (sensor_msgs/Image).

    ``encoding`` is ``bgr8`` (OpenCV channel order) unless it says otherwise; ``step`` is the row
    length in bytes; ``header.stamp`` is the capture time and ``header.frame_id`` the camera name.

    ``data`` decodes as a zero-copy, read-only ``memoryview`` of the received buffer (publishers
    may pass ``bytes``); ``np.frombuffer(msg.data, np.uint8).reshape(h, w, 3)`` views it without a
    copy, and ``.copy()`` gives a writable frame to draw on.
    """

    header: Header = msgspec.field(default_factory=Header)
    height: int = 0
    width: int = 0
    encoding: str = "bgr8"
    is_bigendian: int = 0
    step: int = 0
    data: memoryview = msgspec.field(default_factory=lambda: memoryview(b""))


class CompressedImage(msgspec.Struct, kw_only=True, frozen=True):
    """A compressed image (sensor_msgs/CompressedImage); ``format`` is ``jpeg`` or ``png``.

    ``data`` decodes as a zero-copy, read-only ``memoryview`` (publishers may pass ``bytes``).
    """

    header: Header = msgspec.field(default_factory=Header)
    format: str = "jpeg"
    data: memoryview = msgspec.field(default_factory=lambda: memoryview(b""))


class CameraInfo(msgspec.Struct, kw_only=True, frozen=True):
    """Intrinsics of the frames a camera publishes (sensor_msgs/CameraInfo, ROS 2 names).

    Published alongside each frame with the frame's ``header`` (same stamp and seq), for the
    frame as published (after any flip, rotation, crop or resize).

    Attributes:
        height, width: the frame size the intrinsics are for (px).
        distortion_model: ``plumb_bob`` (d = k1 k2 p1 p2 k3), ``rational_polynomial`` or
            ``equidistant``.
        d: distortion coefficients.
        k: camera matrix, 3x3 row-major (fx 0 cx / 0 fy cy / 0 0 1, px).
        r: rectification rotation, 3x3 row-major (identity for a monocular camera).
        p: projection matrix, 3x4 row-major (px).
    """

    header: Header = msgspec.field(default_factory=Header)
    height: int = 0
    width: int = 0
    distortion_model: str = "plumb_bob"
    d: list[float] = msgspec.field(default_factory=list)
    k: list[float] = msgspec.field(default_factory=lambda: [0.0] * 9)
    r: list[float] = msgspec.field(default_factory=lambda: [0.0] * 9)
    p: list[float] = msgspec.field(default_factory=lambda: [0.0] * 12)


class CameraStatus(msgspec.Struct, kw_only=True, frozen=True):
    """What a camera service is doing, published about once a second.

    Attributes:
        header: ``stamp`` when the status was made, ``frame_id`` the camera name.
        source: what is captured (device path, file, URL, ``pattern``).
        state: ``connecting``, ``streaming``, ``reconnecting`` (lost, retrying with backoff) or
            ``ended`` (a file played once).
        width, height, fps, pixel_format: the mode granted (fps 0 / "" when unknown).
        fps_measured: frames published per second over the last status period (Hz).
        frames_captured: frames read from the source.
        frames_published: frames sent out (on the keys someone subscribes to, or always
            on the JPEG key when the service is told to).
        frames_dropped: captured frames replaced by a newer one before publishing.
        corrupt_frames: failed reads the source recovered from (undecodable frames).
        reconnects: times the source was lost and opened again.
        open_failures: failed attempts to open the source.
        truncated: times a file ended before the frame count its header gives.
        last_error: the most recent error, for a person to read ("" when none).
    """

    header: Header = msgspec.field(default_factory=Header)
    source: str = ""
    state: str = "connecting"
    width: int = 0
    height: int = 0
    fps: float = 0.0
    pixel_format: str = ""
    fps_measured: float = 0.0
    frames_captured: int = 0
    frames_published: int = 0
    frames_dropped: int = 0
    corrupt_frames: int = 0
    reconnects: int = 0
    open_failures: int = 0
    truncated: int = 0
    last_error: str = ""
