"""The SDK's MAVROS constants (written out: the SDK does not depend on pymavlink) are
pymavlink's values, and the DroneWrapper masks are made of the ignore bits they claim."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import mavros

TYPEMASK = "POSITION_TARGET_TYPEMASK_"
SAME_AS_PYMAVLINK = {
    **{
        f"LANDED_STATE_{n}": f"MAV_LANDED_STATE_{n}"
        for n in ("UNDEFINED", "ON_GROUND", "IN_AIR", "TAKEOFF", "LANDING")
    },
    "VTOL_STATE_UNDEFINED": "MAV_VTOL_STATE_UNDEFINED",
    "VTOL_STATE_MC": "MAV_VTOL_STATE_MC",
    **{
        f"FRAME_{n}": f"MAV_FRAME_{n}"
        for n in ("LOCAL_NED", "LOCAL_OFFSET_NED", "BODY_NED", "BODY_OFFSET_NED")
    },
    "IGNORE_PX": TYPEMASK + "X_IGNORE",
    "IGNORE_PY": TYPEMASK + "Y_IGNORE",
    "IGNORE_PZ": TYPEMASK + "Z_IGNORE",
    "IGNORE_VX": TYPEMASK + "VX_IGNORE",
    "IGNORE_VY": TYPEMASK + "VY_IGNORE",
    "IGNORE_VZ": TYPEMASK + "VZ_IGNORE",
    "IGNORE_AFX": TYPEMASK + "AX_IGNORE",
    "IGNORE_AFY": TYPEMASK + "AY_IGNORE",
    "IGNORE_AFZ": TYPEMASK + "AZ_IGNORE",
    "FORCE": TYPEMASK + "FORCE_SET",
    "IGNORE_YAW": TYPEMASK + "YAW_IGNORE",
    "IGNORE_YAW_RATE": TYPEMASK + "YAW_RATE_IGNORE",
    **{
        f"MAV_RESULT_{n}": f"MAV_RESULT_{n}"
        for n in (
            "ACCEPTED",
            "TEMPORARILY_REJECTED",
            "DENIED",
            "UNSUPPORTED",
            "FAILED",
            "IN_PROGRESS",
        )
    },
    **{
        f"SEVERITY_{n}": f"MAV_SEVERITY_{n}"
        for n in ("EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG")
    },
}
# MAV_RESULT_CANCELLED (6) is in the MAVLink standard but not in this pymavlink's common.xml.


@pytest.mark.parametrize(("ours", "theirs"), sorted(SAME_AS_PYMAVLINK.items()))
def test_constant_is_pymavlinks(ours, theirs):
    assert getattr(mavros, ours) == getattr(mavlink, theirs)


def test_masks_ignore_what_they_say():
    m = mavros
    accelerations = m.IGNORE_AFX | m.IGNORE_AFY | m.IGNORE_AFZ
    position = m.IGNORE_PX | m.IGNORE_PY | m.IGNORE_PZ
    velocity = m.IGNORE_VX | m.IGNORE_VY | m.IGNORE_VZ
    unused = accelerations | m.FORCE  # every mask ignores accelerations (and their force flag)
    assert velocity | unused | m.IGNORE_YAW_RATE == m.MASK_POSITION
    assert position | unused | m.IGNORE_YAW == m.MASK_VELOCITY
    assert m.IGNORE_PX | m.IGNORE_PY | unused | m.IGNORE_YAW == m.MASK_MIXED  # z, vx, vy, rate
