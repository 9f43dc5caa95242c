"""Pinhole projection from the vehicle pose: known points land on predicted pixels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dronewrapper_sim.render.camera import (
    FRONTAL,
    VENTRAL,
    CameraMount,
    PinholeCamera,
    project,
    quat_to_matrix,
    yaw_to_quat,
)

CAM = PinholeCamera(640, 480, math.radians(60.0))
AT_ORIGIN = CameraMount("test", np.zeros(3), 0.0)


def test_intrinsics_follow_the_field_of_view():
    assert CAM.fx == pytest.approx(320.0 / math.tan(math.radians(30.0)))
    assert CAM.fy == CAM.fx
    assert (CAM.cx, CAM.cy) == (319.5, 239.5)
    assert CAM.vfov_rad == pytest.approx(2 * math.atan(240.0 / CAM.fy))
    with pytest.raises(ValueError):
        PinholeCamera(640, 480, math.radians(180.0))


def test_a_known_world_point_lands_on_the_predicted_pixel():
    yaw = math.radians(30.0)
    vehicle = np.array([1.0, 2.0, 3.0])
    forward = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    left = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    point = vehicle + 5.0 * forward + 1.0 * left + np.array([0.0, 0.0, 0.5])
    pixels, depth = project(point, vehicle, yaw_to_quat(yaw), AT_ORIGIN, CAM)
    assert depth[0] == pytest.approx(5.0)
    # 1 m left of the axis is left in the image (u smaller); 0.5 m up is up (v smaller)
    assert pixels[0, 0] == pytest.approx(CAM.cx - CAM.fx * 1.0 / 5.0)
    assert pixels[0, 1] == pytest.approx(CAM.cy - CAM.fy * 0.5 / 5.0)


def test_the_frontal_mount_offset_is_applied_in_the_body_frame():
    yaw = math.radians(-90.0)  # facing south
    vehicle = np.array([0.0, 0.0, 2.0])
    cam_pos = vehicle + quat_to_matrix(yaw_to_quat(yaw)) @ FRONTAL.position_flu_m
    point = cam_pos + np.array([0.0, -10.0, 0.0])  # 10 m straight ahead of the camera
    pixels, depth = project(point, vehicle, yaw_to_quat(yaw), FRONTAL, CAM)
    assert depth[0] == pytest.approx(10.0)
    assert pixels[0] == pytest.approx([CAM.cx, CAM.cy])


def test_nose_down_pitch_moves_the_horizon_up():
    pitch = math.radians(10.0)  # rotation about body +y (left): nose down in FLU
    quat = np.array([0.0, math.sin(pitch / 2), 0.0, math.cos(pitch / 2)])
    point = np.array([20.0, 0.0, 0.0])  # level, straight ahead
    pixels, _ = project(point, np.zeros(3), quat, AT_ORIGIN, CAM)
    assert pixels[0, 0] == pytest.approx(CAM.cx)
    assert pixels[0, 1] == pytest.approx(CAM.cy - CAM.fy * math.tan(pitch))


def test_ventral_camera_looks_down_with_forward_at_the_image_top():
    vehicle = np.array([3.0, 4.0, 10.0])
    quat = yaw_to_quat(0.0)  # facing east
    mount = CameraMount("down", np.zeros(3), VENTRAL.pitch_rad)
    below = np.array([3.0, 4.0, 0.0])
    ahead = np.array([5.0, 4.0, 0.0])  # 2 m east = forward
    left = np.array([3.0, 6.0, 0.0])  # 2 m north = left
    pixels, depth = project(np.array([below, ahead, left]), vehicle, quat, mount, CAM)
    assert depth == pytest.approx([10.0, 10.0, 10.0])
    assert pixels[0] == pytest.approx([CAM.cx, CAM.cy])
    assert pixels[1] == pytest.approx([CAM.cx, CAM.cy - CAM.fy * 0.2])
    assert pixels[2] == pytest.approx([CAM.cx - CAM.fx * 0.2, CAM.cy])


def test_points_behind_the_camera_are_culled():
    points = np.array([[-5.0, 0.0, 0.0], [0.01, 0.0, 0.0], [5.0, 0.0, 0.0]])
    pixels, depth = project(points, np.zeros(3), yaw_to_quat(0.0), AT_ORIGIN, CAM)
    assert depth[0] == pytest.approx(-5.0)
    assert np.all(np.isnan(pixels[0])) and np.all(np.isnan(pixels[1]))
    assert np.all(np.isfinite(pixels[2]))


def test_an_invalid_quaternion_is_refused():
    with pytest.raises(ValueError):
        project(np.ones(3), np.zeros(3), np.zeros(4), AT_ORIGIN, CAM)
    with pytest.raises(ValueError):
        project(np.ones(3), np.zeros(3), np.array([0, 0, math.nan, 1]), AT_ORIGIN, CAM)
