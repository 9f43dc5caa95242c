"""bridge_base.flight_request: the flight-request rules both PX4 bridges share."""

import math

import pytest

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.flight import NO_HOME, REFUSED, FlightResult, GotoRequest
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, LANDED_STATE_ON_GROUND
from dronewrapper_bridge_base.flight_request import (
    goto_target,
    land_point,
    takeoff_command,
    takeoff_heights,
    took_off,
)


class Home:
    def __init__(self, home_geo=None) -> None:
        self.envelope = Envelope(max_distance=50.0, max_altitude=20.0)
        self.home_local = (1.0, 2.0, 0.5)
        self.home_geo = home_geo


def test_a_goto_flies_to_the_point_from_home():
    assert goto_target(Home(), GotoRequest(x=3.0, y=4.0, z=5.0)) == (4.0, 6.0, 5.5)


def test_a_goto_outside_the_envelope_is_refused_naming_it():
    refusal = goto_target(Home(), GotoRequest(x=100.0, y=0.0, z=5.0))
    assert isinstance(refusal, FlightResult) and refusal.failure == REFUSED
    assert refusal.step == "goto"


@pytest.mark.parametrize("home_geo", [None, (math.nan, math.nan, math.nan)])
def test_a_geodetic_goto_needs_home_latitude_and_longitude(home_geo):
    request = GotoRequest(latitude=47.0, longitude=8.0, z=5.0)
    refusal = goto_target(Home(home_geo), request)
    assert isinstance(refusal, FlightResult) and refusal.failure == NO_HOME


def test_a_takeoff_climbs_from_the_ground_or_from_the_origin_mid_landing():
    assert takeoff_heights(0.3, LANDED_STATE_ON_GROUND, 2.0) == (0.3, 2.3)
    assert takeoff_heights(4.0, LANDED_STATE_IN_AIR, 2.0) == (0.0, 2.0)
    result = took_off(2.25, 0.25, 2.0)
    assert result.success and result.height == 2.0


@pytest.mark.parametrize(
    ("lat", "lon", "named"),
    [(91.0, 0.0, "latitude"), (0.0, -181.0, "longitude"), (math.inf, 0.0, "latitude")],
)
def test_a_landing_point_out_of_bounds_is_a_bad_request(lat, lon, named):
    with pytest.raises(ValueError, match=named):
        land_point(lat, lon)


def test_a_landing_point_may_be_nan_for_here():
    lat, lon = land_point(math.nan, math.nan)
    assert math.isnan(lat) and math.isnan(lon)


@pytest.mark.parametrize(
    ("height", "yaw", "named"),
    [
        (0.0, 0.0, "altitude"),
        (1001.0, 0.0, "altitude"),
        (math.inf, 0.0, "altitude"),
        (2.0, math.inf, "yaw"),
    ],
)
def test_a_takeoff_command_out_of_bounds_is_a_bad_request(height, yaw, named):
    with pytest.raises(ValueError, match=named):
        takeoff_command(height, yaw)


def test_a_takeoff_command_yaw_is_degrees_ned_and_nan_is_the_autopilots_default():
    assert takeoff_command(2.0, 0.0) == (2.0, 90.0)  # ENU east is NED 90 degrees
    height, yaw_deg = takeoff_command(math.nan, math.nan)
    assert math.isnan(height) and math.isnan(yaw_deg)
