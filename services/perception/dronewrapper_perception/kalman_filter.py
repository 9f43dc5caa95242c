"""A constant-velocity Kalman filter for one image box, pure numpy, time passed in.

State ``[cx, cy, w, h, vcx, vcy, vw, vh]``: box centre and size in px, their rates in px/s.
Measurement ``[cx, cy, w, h]`` in px. Noise scales with the box height so near (large) and far
(small) people behave alike: process noise is white acceleration of ``accel_std`` box heights
per s², measurement noise ``meas_std`` box heights.
"""

from __future__ import annotations

import numpy as np

_H = np.hstack((np.eye(4), np.zeros((4, 4))))


class BoxKalmanFilter:
    """Constant-velocity filter on (cx, cy, w, h); ``t`` in seconds (any monotonic clock)."""

    def __init__(
        self,
        box_cxcywh: np.ndarray | tuple[float, float, float, float],
        t: float,
        *,
        accel_std: tuple[float, float] = (2.0, 0.5),
        meas_std: tuple[float, float] = (0.05, 0.1),
        init_vel_std: tuple[float, float] = (1.0, 0.2),
    ) -> None:
        """Args: accel_std/meas_std/init_vel_std as (position, size) in box heights."""
        z = np.asarray(box_cxcywh, dtype=np.float64)
        self.x = np.concatenate((z, np.zeros(4)))
        h = max(z[3], 1.0)
        pos_std, size_std = meas_std[0] * h, meas_std[1] * h
        vel_std, svel_std = init_vel_std[0] * h, init_vel_std[1] * h
        self.P = np.diag(
            np.square([pos_std, pos_std, size_std, size_std, vel_std, vel_std, svel_std, svel_std])
        )
        self.t = t
        self.accel_std = accel_std
        self.meas_std = meas_std

    @property
    def box_cxcywh(self) -> np.ndarray:
        """The current estimate (cx, cy, w, h) in px."""
        return self.x[:4].copy()

    @property
    def velocity(self) -> np.ndarray:
        """Rates (vcx, vcy, vw, vh) in px/s."""
        return self.x[4:].copy()

    def _height(self) -> float:
        return float(max(self.x[3], 1.0))

    def predict(self, t: float) -> None:
        """Advance the state to time ``t`` (no-op if ``t`` is not later)."""
        dt = t - self.t
        if dt <= 0:
            return
        F = np.eye(8)
        F[:4, 4:] = np.eye(4) * dt
        h = self._height()
        q = np.array([self.accel_std[0], self.accel_std[0], self.accel_std[1], self.accel_std[1]])
        q = np.square(q * h)
        Q = np.zeros((8, 8))
        Q[:4, :4] = np.diag(q * dt**4 / 4)
        Q[:4, 4:] = Q[4:, :4] = np.diag(q * dt**3 / 2)
        Q[4:, 4:] = np.diag(q * dt**2)
        self.x = F @ self.x
        self.x[2:4] = np.maximum(self.x[2:4], 1.0)
        self.P = F @ self.P @ F.T + Q
        self.t = t

    def _innovation_cov(self) -> np.ndarray:
        h = self._height()
        r = np.square(
            np.array([self.meas_std[0], self.meas_std[0], self.meas_std[1], self.meas_std[1]]) * h
        )
        return _H @ self.P @ _H.T + np.diag(r)

    def mahalanobis_sq(self, boxes_cxcywh: np.ndarray) -> np.ndarray:
        """Squared Mahalanobis distance of each measurement row to the predicted box."""
        z = np.atleast_2d(np.asarray(boxes_cxcywh, dtype=np.float64))
        d = z - self.x[:4]
        S_inv = np.linalg.inv(self._innovation_cov())
        return np.einsum("ij,jk,ik->i", d, S_inv, d)

    def update(self, box_cxcywh: np.ndarray | tuple[float, float, float, float]) -> None:
        """Correct the state with a measured box (cx, cy, w, h) in px."""
        z = np.asarray(box_cxcywh, dtype=np.float64)
        S = self._innovation_cov()
        K = self.P @ _H.T @ np.linalg.inv(S)
        self.x = self.x + K @ (z - self.x[:4])
        self.P = (np.eye(8) - K @ _H) @ self.P
