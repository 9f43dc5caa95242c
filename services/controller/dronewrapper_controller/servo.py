"""The visual-servoing state machine: detections in, a body-frame velocity command out.

Pure: no I/O and no clock. Each :meth:`Servo.step` gets ``now`` (seconds on a monotonic clock,
used for the target-lost timings), the newest :class:`Detections` (or None) and its age (s).
The PIDs use the detections' own ``header.stamp`` (the camera frame's capture time) for their
time steps, so dt is the real interval between the frames that were measured.

States (``dronewrapper.msgs.control``):
- ``tracking``: fresh detections contain the target; vx, vz, yaw rate from the three PIDs,
  vy is always 0. A tick without a new frame repeats the last command.
- ``hover``: detections are stale (older than ``detection_timeout``: perception stopped or
  lags), or the target was lost only a moment ago; all-zero command, PIDs reset. A dropout
  shorter than ``lost_hold`` (a frame or two without the target) keeps the last command.
- ``search``: detections are fresh but the target has been missing for ``search_delay`` s
  (it was last seen near the left or right border, within ``edge_margin`` of it: it left the
  view) or ``occlusion_delay`` s (it vanished inside the image: most likely hidden behind
  someone, so turning away would lose it for good): turn in place at ``search_yaw_rate``
  towards the side where it was last seen. Search needs live perception: with stale
  detections the aircraft hovers rather than spinning blind.
"""

from __future__ import annotations

import math

import msgspec

from dronewrapper.msgs.control import (
    CONTROLLER_HOVER,
    CONTROLLER_SEARCH,
    CONTROLLER_TRACKING,
)
from dronewrapper.msgs.vision import Detection2D, Detections
from dronewrapper_controller.config import ServoConfig
from dronewrapper_controller.errors import (
    ServoErrors,
    finite,
    follow_color_errors,
    follow_person_errors,
)
from dronewrapper_controller.pid import Pid


class Command(msgspec.Struct, kw_only=True, frozen=True):
    """One decision of the servo.

    Attributes:
        state: ``tracking``, ``hover`` or ``search``.
        vx, vz, yaw_rate: body FLU forward and vertical speed (m/s) and yaw rate (rad/s,
            counter-clockwise positive); vy is always 0.
        source_stamp: capture stamp of the frame behind this command (0 when none).
        target_visible: the fresh detections contain the target.
        target_id: the followed detection's id ("" when none or untracked).
        errors: the error terms of the frame behind the command (None when not tracking).
    """

    state: str
    vx: float = 0.0
    vz: float = 0.0
    yaw_rate: float = 0.0
    source_stamp: float = 0.0
    target_visible: bool = False
    target_id: str = ""
    errors: ServoErrors | None = None


def pick_target(detections: Detections, *, best_when_untargeted: bool) -> Detection2D | None:
    """The followed detection.

    The tracker's target when it names one. Otherwise: with ``best_when_untargeted`` (colour:
    the paper follows the largest blob, identity does not matter) the best (first) detection;
    without it (people: never jump to a passer-by while the target is hidden) none, unless the
    detections carry no track ids at all (no tracker runs), then the best one.
    """
    if detections.target_id:
        return detections.target()
    if not best_when_untargeted and any(det.id for det in detections.detections):
        return None
    return detections.detections[0] if detections.detections else None


class Servo:
    """Three PIDs and the tracking / hover / search logic for one follow mode."""

    def __init__(self, config: ServoConfig) -> None:
        self.config = config
        mode = config.follow_color if config.mode == "follow_color" else config.follow_person
        vx_gains = mode.vx
        self._best_when_untargeted = mode.best_when_untargeted
        self._switch_confirm = mode.id_switch_confirm
        self._followed_id = ""  # track id being followed ("" before the first / untracked)
        self._candidate: tuple[str, float] = ("", 0.0)  # a new target id and since when
        self.pid_vx = Pid(vx_gains)
        self.pid_vz = Pid(config.vz)
        self.pid_yaw = Pid(config.yaw_rate)
        self._last_seen: float | None = None  # `now` when the target was last in a frame
        self._last_stamp: float | None = None  # stamp of the last frame used
        self._last_yaw_error = 0.0
        self._last: Command = Command(state=CONTROLLER_HOVER)

    @property
    def last(self) -> Command:
        """The last command returned by :meth:`step`."""
        return self._last

    def reset(self) -> None:
        """Reset the three PIDs (called whenever the servo stops tracking)."""
        for pid in (self.pid_vx, self.pid_vz, self.pid_yaw):
            pid.reset()

    def errors_for(self, det: Detection2D, detections: Detections) -> ServoErrors:
        """The mode's error terms for ``det`` in a frame of ``detections``' size."""
        c = self.config
        w, h = detections.image_width, detections.image_height
        if c.mode == "follow_color":
            return follow_color_errors(det, w, h, c.follow_color.target_radius, c.ref_width)
        fp = c.follow_person
        return follow_person_errors(det, w, h, fp.area_ratio, fp.max_forward_error, c.ref_width)

    def _confirmed(self, now: float, track_id: str) -> bool:
        """Whether to steer on track ``track_id`` now: the followed track, the first one, an
        untracked detection, or a new id that has stayed the target for ``id_switch_confirm`` s
        (a tracker that picks a passer-by for a frame or two must not swing the drone). While
        searching, the target is truly lost: whatever the tracker names is taken at once."""
        searching = self._last.state == CONTROLLER_SEARCH  # truly lost: take what is named
        if (
            not track_id
            or self._followed_id in ("", track_id)
            or self._switch_confirm <= 0
            or searching
        ):
            self._followed_id = track_id
            self._candidate = ("", 0.0)
            return True
        candidate, since = self._candidate
        if candidate != track_id:
            self._candidate = (track_id, now)
            return False
        if now - since >= self._switch_confirm:
            self._followed_id = track_id
            self._candidate = ("", 0.0)
            return True
        return False

    def _find(
        self, now: float, detections: Detections | None, age: float
    ) -> tuple[bool, Detection2D | None, ServoErrors | None]:
        """(fresh, target, errors): target and errors are None when it is not usable."""
        fresh = detections is not None and age <= self.config.detection_timeout
        target = (
            pick_target(detections, best_when_untargeted=self._best_when_untargeted)
            if fresh and detections is not None
            else None
        )
        if target is None or detections is None or not self._confirmed(now, target.id):
            return fresh, None, None
        try:
            errors = self.errors_for(target, detections)
        except ValueError:  # malformed frame size: treat as no target
            return fresh, None, None
        if not finite(errors):
            return fresh, None, None
        return fresh, target, errors

    def observe(self, now: float, detections: Detections | None, age: float) -> bool:
        """Watch without commanding (e.g. during take-off): remember when and on which side the
        target was last seen, so a later search turns the right way. True if it is in view."""
        _, _, errors = self._find(now, detections, age)
        if errors is None:
            return False
        self._last_seen = now
        self._last_yaw_error = errors.yaw
        return True

    def step(self, now: float, detections: Detections | None, age: float) -> Command:
        """Decide the command at time ``now`` (s) from the newest detections, ``age`` s old."""
        fresh, target, errors = self._find(now, detections, age)
        if errors is None or detections is None or target is None:
            return self._not_tracking(now, fresh)

        self._last_seen = now
        self._last_yaw_error = errors.yaw
        stamp = detections.header.stamp
        if self._last.state == CONTROLLER_TRACKING and stamp == self._last_stamp:
            return self._last  # same frame: repeat the command
        self._last_stamp = stamp
        self._last = Command(
            state=CONTROLLER_TRACKING,
            vx=self.pid_vx.update(errors.x, stamp),
            vz=self.pid_vz.update(errors.z, stamp),
            yaw_rate=self.pid_yaw.update(errors.yaw, stamp),
            source_stamp=stamp,
            target_visible=True,
            target_id=target.id,
            errors=errors,
        )
        return self._last

    def _not_tracking(self, now: float, fresh: bool) -> Command:
        lost_for = math.inf if self._last_seen is None else now - self._last_seen
        if fresh and self._last.state == CONTROLLER_TRACKING and lost_for <= self.config.lost_hold:
            return self._last  # a dropout of a frame or two: keep the last command
        self.reset()
        self._last_stamp = None
        half = self.config.ref_width / 2.0
        left_the_view = abs(self._last_yaw_error) >= half * (1.0 - self.config.edge_margin)
        delay = (
            self.config.search_delay
            if left_the_view or self._last_seen is None
            else self.config.occlusion_delay
        )
        if fresh and lost_for >= delay:
            direction = 1.0 if self._last_yaw_error >= 0 else -1.0
            self._last = Command(
                state=CONTROLLER_SEARCH, yaw_rate=direction * self.config.search_yaw_rate
            )
        else:
            self._last = Command(state=CONTROLLER_HOVER)
        return self._last
