"""PX4's commander and navigator, as seen from MAVLink: modes, arming, take-off, landing,
auto-disarm and the offboard-loss failsafe. A pure state machine: time comes in as ``now``
(seconds, any monotonic origin) and the true vehicle state as a :class:`QuadState`.

Reproduced PX4 behaviour (measured on PX4 SITL, see sim/README.md):
- a mode change while disarmed is always accepted; while armed the mode must be able to run
  (OFFBOARD needs a fresh setpoint stream, manual modes need RC, which this vehicle lacks),
  else TEMPORARILY_REJECTED with "Switching to <mode> is currently not available" (the
  autopilot sends this result as the second of DO_SET_MODE's two acks, after an ACCEPTED);
- arming is refused (TEMPORARILY_REJECTED, "Arming denied: Resolve system health failures
  first") when the intended mode cannot run: OFFBOARD with no setpoint stream, manual modes,
  MISSION (no mission), LAND and RTL;
- auto-disarm COM_DISARM_PRFLT s after arming without take-off, COM_DISARM_LAND s after
  "Landing detected" (LNDMC_TRIG_TIME s of ground contact);
- NAV_TAKEOFF -> AUTO.TAKEOFF to MIS_TAKEOFF_ALT above home (or an AMSL altitude), climbing at
  MPC_TKO_SPEED, then AUTO.LOITER; NAV_LAND -> AUTO.LAND with PX4's descent-speed schedule;
- OFFBOARD: the signal is lost COM_OF_LOSS_T s after the last setpoint -> "Failsafe
  activated" and the fallback (COM_OBL_RC_ACT, and NAV_RCL_ACT when that needs RC): RTL by
  default; not latched: the vehicle is back in OFFBOARD as soon as setpoints resume;
- after a disarm, a LAND or RTL intention reverts to the mode intended before it;
- RTL and AUTO.LAND fly as :mod:`~dronewrapper_sim.px4.rtl` says, AUTO.MISSION as
  :mod:`~dronewrapper_sim.px4.mission`, the geofence as :mod:`~dronewrapper_sim.px4.geofence`.

Size: PX4's mode and arming rules are one state machine, each rule next to the PX4 behaviour
it reproduces; what each auto mode flies is in the modules named above.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.dynamics import QuadState
from dronewrapper_sim.px4 import geofence, mission, rtl
from dronewrapper_sim.px4.flight_control import NAN, Target
from dronewrapper_sim.px4.modes import NAV_NAMES, Mode
from dronewrapper_sim.px4.offboard import OffboardSetpoint
from dronewrapper_sim.px4.params import ParamStore

# MAV_RESULT

# MAV_SEVERITY

ARM_DENIED = "Arming denied: Resolve system health failures first"
FORCE_MAGIC = 21196  # COMPONENT_ARM_DISARM param2 that forces arm/disarm


class LandedState(IntEnum):
    """MAV_LANDED_STATE."""

    UNDEFINED = mavlink.MAV_LANDED_STATE_UNDEFINED
    ON_GROUND = mavlink.MAV_LANDED_STATE_ON_GROUND
    IN_AIR = mavlink.MAV_LANDED_STATE_IN_AIR
    TAKEOFF = mavlink.MAV_LANDED_STATE_TAKEOFF
    LANDING = mavlink.MAV_LANDED_STATE_LANDING


# COM_OBL_RC_ACT -> mode (None: needs RC -> fall back to NAV_RCL_ACT); NAV_RCL_ACT -> mode
_OBL_ACTIONS = {0: None, 1: None, 2: None, 3: Mode.RTL, 4: Mode.LAND, 5: Mode.LOITER}
_RCL_ACTIONS = {0: Mode.LOITER, 1: Mode.LOITER, 2: Mode.RTL, 3: Mode.LAND}


@dataclass(frozen=True)
class StatusText:
    """A message for the ground station (MAV_SEVERITY, text as PX4 writes it)."""

    severity: int
    text: str


class Commander:
    """Modes, arming, navigation and failsafes of one vehicle.

    Args:
        params: the vehicle's parameters (read live, so PARAM_SET takes effect).
        start: the vehicle's state at boot (home and the initial hold point).
    """

    def __init__(self, params: ParamStore, start: QuadState) -> None:
        self.params = params
        self.armed = False
        self.armed_at = -math.inf
        self.user_mode = Mode.LOITER
        self.nav_mode = Mode.LOITER
        self._mode_before_auto: Mode | None = None
        self.failsafe = False
        self.landed = True
        self.landed_at = -math.inf
        self._contact_since: float | None = None
        self.taken_off_since_arming = False
        self.takeoff_started_at: float | None = None
        self.setpoint: OffboardSetpoint | None = None
        self.setpoint_at = -math.inf
        self.home = (start.x, start.y, start.z)
        self.home_yaw = start.yaw
        self.texts: list[StatusText] = []
        self.target = Target(idle=True)
        self._last_reject_text = -math.inf
        # navigator
        self._hold = (start.x, start.y, start.z, start.yaw)
        self._takeoff_z = start.z
        self._rtl = rtl.ReturnFlight(self.home)
        self.rally_points: Callable[[], list[tuple[float, float]]] = list  # local ENU m
        self.mission: mission.MissionRunner | None = None  # set by the autopilot
        self.geofence: geofence.Geofence | None = None

    # ---- helpers ----

    def _say(self, severity: int, text: str) -> None:
        self.texts.append(StatusText(severity, text))

    def drain_texts(self) -> list[StatusText]:
        """The status texts produced since the last call."""
        out, self.texts = self.texts, []
        return out

    def offboard_available(self, now: float) -> bool:
        """A setpoint arrived within COM_OF_LOSS_T seconds."""
        return now - self.setpoint_at <= self.params["COM_OF_LOSS_T"]

    def _can_run(self, mode: Mode, now: float) -> bool:
        if mode is Mode.MISSION and self.mission is not None:
            return self.mission.runnable()
        if mode.needs_rc or mode in (Mode.MISSION, Mode.FOLLOWME, Mode.PRECLAND):
            return False
        return mode is not Mode.OFFBOARD or self.offboard_available(now)

    def _reject_mode_text(self, mode: Mode, now: float) -> None:
        if now - self._last_reject_text > 1.0:
            self._last_reject_text = now
            self._say(
                mavlink.MAV_SEVERITY_CRITICAL,
                f"Switching to {NAV_NAMES[mode]} is currently not available",
            )

    @property
    def landed_state(self) -> LandedState:
        """MAV_LANDED_STATE for EXTENDED_SYS_STATE."""
        if self.landed:
            return LandedState.ON_GROUND
        if self.nav_mode is Mode.TAKEOFF:
            return LandedState.TAKEOFF
        if self.nav_mode is Mode.LAND or (self.nav_mode is Mode.RTL and self._rtl.phase == "land"):
            return LandedState.LANDING
        return LandedState.IN_AIR

    # ---- commands (return a MAV_RESULT) ----

    def arm(self, now: float, state: QuadState, force: bool = False) -> int:
        """COMPONENT_ARM_DISARM param1 = 1."""
        if self.armed:
            return mavlink.MAV_RESULT_ACCEPTED
        if not force and not self._can_run(self.user_mode, now):
            self._say(mavlink.MAV_SEVERITY_CRITICAL, ARM_DENIED)
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        if not force and self.user_mode in (Mode.LAND, Mode.RTL):
            self._say(mavlink.MAV_SEVERITY_CRITICAL, ARM_DENIED)
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        self.armed = True
        self.armed_at = now
        self.landed_at = now
        self.taken_off_since_arming = False
        self.takeoff_started_at = None
        self.home = (state.x, state.y, state.z)
        self.home_yaw = state.yaw
        self._say(mavlink.MAV_SEVERITY_INFO, "Armed by external command")
        self._enter(self.nav_mode, state, now)
        return mavlink.MAV_RESULT_ACCEPTED

    def disarm(self, now: float, state: QuadState, force: bool = False, reason: str = "") -> int:
        """COMPONENT_ARM_DISARM param1 = 0 (refused in the air unless forced)."""
        if not self.armed:
            return mavlink.MAV_RESULT_ACCEPTED
        if not self.landed and not force:
            self._say(mavlink.MAV_SEVERITY_CRITICAL, "Disarming denied: not landed")
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        self.armed = False
        self.failsafe = False
        self._say(mavlink.MAV_SEVERITY_INFO, reason or "Disarmed by external command")
        if self.user_mode in (Mode.LAND, Mode.RTL) and self._mode_before_auto is not None:
            self.user_mode = self._mode_before_auto
        self._mode_before_auto = None
        self._enter(self.user_mode, state, now)
        return mavlink.MAV_RESULT_ACCEPTED

    def set_mode(self, mode: Mode, now: float, state: QuadState) -> int:
        """DO_SET_MODE / SET_MODE: change the user-intended mode."""
        if self.armed and not self._can_run(mode, now):
            self._reject_mode_text(mode, now)
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        if mode in (Mode.LAND, Mode.RTL) and self.user_mode not in (Mode.LAND, Mode.RTL):
            self._mode_before_auto = self.user_mode
        elif mode not in (Mode.LAND, Mode.RTL):
            self._mode_before_auto = None
        self.user_mode = mode
        self.failsafe = False
        if mode is Mode.TAKEOFF:
            self._takeoff_z = self.home[2] + self.params["MIS_TAKEOFF_ALT"]
        self._enter(mode, state, now)
        return mavlink.MAV_RESULT_ACCEPTED

    def takeoff(self, now: float, state: QuadState, altitude_above_home: float = NAN) -> int:
        """NAV_TAKEOFF: AUTO.TAKEOFF to ``altitude_above_home`` (m) or MIS_TAKEOFF_ALT."""
        result = self.set_mode(Mode.TAKEOFF, now, state)
        if result == mavlink.MAV_RESULT_ACCEPTED and math.isfinite(altitude_above_home):
            self._takeoff_z = self.home[2] + altitude_above_home
        if result == mavlink.MAV_RESULT_ACCEPTED and self._takeoff_z < state.z:
            self._takeoff_z = state.z
        return result

    def on_setpoint(self, setpoint: OffboardSetpoint, now: float) -> None:
        """An accepted offboard setpoint arrived."""
        self.setpoint = setpoint
        self.setpoint_at = now

    # ---- time passes ----

    def update(self, now: float, state: QuadState) -> None:
        """Land detector, auto-disarm, failsafes and navigator progress at time ``now``."""
        self._land_detector(now, state)
        if self.armed and self.landed:
            if self.taken_off_since_arming:
                timeout, reason = self.params["COM_DISARM_LAND"], "Disarmed by landing"
            else:
                timeout, reason = (
                    self.params["COM_DISARM_PRFLT"],
                    "Disarmed by auto preflight disarming",
                )
            if timeout > 0 and now - self.landed_at >= timeout:
                self.disarm(now, state, force=True, reason=reason)
        self._offboard_failsafe(now, state)
        self.check_geofence(now, state)
        self._navigate(now, state)

    def _land_detector(self, now: float, state: QuadState) -> None:
        if not self.armed:
            if state.on_ground and not self.landed:
                self.landed, self.landed_at = True, now
            self._contact_since = None
            return
        if self.landed:
            if not state.on_ground and state.z > 0.05:
                self.landed = False
                self.taken_off_since_arming = True
                self._contact_since = None
                self._say(mavlink.MAV_SEVERITY_INFO, "Takeoff detected")
            return
        resting = state.on_ground or (state.z < 0.03 and abs(state.vz) < 0.1)
        if resting:
            if self._contact_since is None:
                self._contact_since = now
            if now - self._contact_since >= self.params["LNDMC_TRIG_TIME"]:
                self.landed, self.landed_at = True, now
                self.takeoff_started_at = None
                self._say(mavlink.MAV_SEVERITY_INFO, "Landing detected")
        else:
            self._contact_since = None

    def _fallback_mode(self) -> Mode:
        action = _OBL_ACTIONS.get(int(self.params["COM_OBL_RC_ACT"]))
        if action is None:  # needs RC, which this vehicle has not got
            action = _RCL_ACTIONS.get(int(self.params["NAV_RCL_ACT"]), Mode.RTL)
        return action

    def _offboard_failsafe(self, now: float, state: QuadState) -> None:
        in_offboard = self.armed and self.user_mode is Mode.OFFBOARD
        if not in_offboard:
            self.failsafe = False
            if self.nav_mode is not self.user_mode:
                self._enter(self.user_mode, state, now)
            return
        available = self.offboard_available(now)
        if not available and not self.failsafe:
            self.failsafe = True
            self._say(mavlink.MAV_SEVERITY_CRITICAL, "Failsafe activated")
            self._enter(self._fallback_mode(), state, now)
        elif available and self.failsafe:
            self.failsafe = False  # not latched: OFFBOARD is still what the user wants
            self._enter(Mode.OFFBOARD, state, now)

    # ---- navigator ----

    def _enter(self, mode: Mode, state: QuadState, now: float) -> None:
        self.nav_mode = mode
        self._hold = (state.x, state.y, state.z, state.yaw)
        if mode is Mode.RTL:
            self._start_rtl(state)

    def _navigate(self, now: float, state: QuadState) -> None:
        p = self.params
        auto_yaw_rate = math.radians(p["MPC_YAWRAUTO_MAX"])
        _hx, _hy, _hz = self.home
        x0, y0, z0, yaw0 = self._hold
        mode = self.nav_mode
        target: Target
        if mode is Mode.OFFBOARD:
            sp = self.setpoint
            if sp is None:
                target = Target(position=(x0, y0, z0), yaw=yaw0)
            else:
                target = Target(
                    position=sp.position,
                    velocity=sp.velocity,
                    acceleration=sp.acceleration,
                    yaw=sp.yaw,
                    yaw_rate=sp.yaw_rate,
                    max_xy=p["MPC_XY_VEL_MAX"],
                    max_up=p["MPC_Z_VEL_MAX_UP"],
                    max_down=p["MPC_Z_VEL_MAX_DN"],
                    max_yaw_rate=math.radians(p["MC_YAWRATE_MAX"]),
                )
        elif mode is Mode.TAKEOFF:
            target = Target(
                position=(x0, y0, self._takeoff_z),
                yaw=yaw0,
                max_xy=p["MPC_XY_CRUISE"],
                max_up=p["MPC_TKO_SPEED"],
                max_down=p["MPC_Z_V_AUTO_DN"],
                max_yaw_rate=auto_yaw_rate,
            )
            if self.armed and not self.landed and abs(state.z - self._takeoff_z) < 0.1:
                self.user_mode = Mode.LOITER
                self._enter(Mode.LOITER, state, now)
                self._hold = (x0, y0, self._takeoff_z, yaw0)
        elif mode is Mode.LAND:
            target = rtl.land_target(p, self.home[2], x0, y0, yaw0, state.z)
        elif mode is Mode.RTL:
            target, text = self._rtl.target(p, state, now, self._hold)
            if text:
                self._say(mavlink.MAV_SEVERITY_INFO, text)
        elif mode is Mode.MISSION and self.mission is not None:
            target = self._mission_target(self.mission, now, state)
        else:  # LOITER and anything that cannot fly: hold where the mode started
            target = Target(
                position=(x0, y0, z0),
                yaw=yaw0,
                max_xy=p["MPC_XY_CRUISE"],
                max_up=p["MPC_Z_V_AUTO_UP"],
                max_down=p["MPC_Z_V_AUTO_DN"],
                max_yaw_rate=auto_yaw_rate,
            )
        self.target = self._ground_handling(target, now, state)

    def _start_rtl(self, state: QuadState) -> None:
        text = self._rtl.start(self.params, state, self.landed, self.home, self.rally_points())
        if text:
            self._say(mavlink.MAV_SEVERITY_INFO, text)

    def check_geofence(self, now: float, state: QuadState) -> None:
        """A fence breach in the air starts GF_ACTION once per excursion (PX4's geofence)."""
        if self.geofence is None or not self.armed or self.landed:
            return
        breach = self.geofence.check(self.params["GF_ACTION"], state.x, state.y)
        if breach is None:
            return
        self._say(mavlink.MAV_SEVERITY_CRITICAL, geofence.BREACH_TEXT)
        if breach.mode is not None and self.nav_mode is not breach.mode:
            self.set_mode(breach.mode, now, state)

    def _mission_target(
        self, runner: mission.MissionRunner, now: float, state: QuadState
    ) -> Target:
        """AUTO.MISSION: the runner's leg, or at its end the mode the mission ends in."""
        leg = runner.step(now, (state.x, state.y, state.z))
        for text in runner.notes:
            self._say(mavlink.MAV_SEVERITY_INFO, text)
        runner.notes.clear()
        if leg.position is None:
            if leg.mode == "loiter":
                self._say(mavlink.MAV_SEVERITY_INFO, "Mission finished, loitering")
            end = {"loiter": Mode.LOITER, "land": Mode.LAND, "rtl": Mode.RTL}[leg.mode]
            self.set_mode(end, now, state)
        target, self._hold = mission.leg_target(leg, self.params, self._hold, state)
        return target

    def _ground_handling(self, target: Target, now: float, state: QuadState) -> Target:
        """Motors off when disarmed; idle during spool-up and while landed unless the target
        asks to climb; PX4's take-off ramp limits the climb speed right after lift-off."""
        if not self.armed:
            return Target(idle=True)
        if now - self.armed_at < self.params["COM_SPOOLUP_TIME"]:
            return Target(idle=True)
        if self.landed:
            wants_up = (
                math.isfinite(target.position[2]) and target.position[2] > state.z + 0.2
            ) or (
                not math.isfinite(target.position[2])
                and math.isfinite(target.velocity[2])
                and target.velocity[2] > 0.3
            )
            if not wants_up:
                self.takeoff_started_at = None
                return Target(idle=True)
            if self.takeoff_started_at is None:
                self.takeoff_started_at = now
        if self.takeoff_started_at is not None:
            ramp_t = self.params["MPC_TKO_RAMP_T"]
            frac = 1.0 if ramp_t <= 0 else min(1.0, (now - self.takeoff_started_at) / ramp_t)
            if frac >= 1.0 and not self.landed:
                self.takeoff_started_at = None
            else:
                max_up = max(0.3, frac * target.max_up)
                return Target(
                    position=target.position,
                    velocity=target.velocity,
                    acceleration=target.acceleration,
                    yaw=target.yaw,
                    yaw_rate=target.yaw_rate,
                    max_xy=target.max_xy,
                    max_up=max_up,
                    max_down=target.max_down,
                    max_yaw_rate=target.max_yaw_rate,
                )
        return target
