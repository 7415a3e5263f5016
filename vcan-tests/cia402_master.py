"""A CiA 402 master (drives and motion control) for the vcan tests, over canopen_master.

Written from the text of CiA 402-2 (= IEC 61800-7-201/-301, CANopen mapping), not from the
node's code:

- the power drive system (PDS) state machine of 6041h/6040h: a state is decoded from the
  statusword with the standard's masks (0x4F for the states whose bit 5 is "don't care",
  0x6F for the others), a state change is commanded with the controlword's command
  coding, and each step is awaited with python-canopen's per-step timeout (0.4 s,
  BaseNode402.TIMEOUT_SWITCH_STATE_SINGLE);
- the profile position (pp) set-point handshake: target 607Ah, then controlword bit 4
  "new set-point" -> statusword bit 12 "set-point acknowledge" -> bit 4 cleared -> bit 12
  cleared; bit 5 "change set immediately", bit 6 "absolute/relative", bit 8 "halt"; bit 10
  "target reached";
- the profile velocity (pv) mode: target 60FFh, bit 10 "target reached" (velocity reached),
  bit 12 "speed" (1 = speed is 0).

The drive is driven over its default RPDOs and observed through its default TPDOs (CiA
402-2 "pre-defined PDO mapping", COB-IDs of CiA 301's pre-defined connection set): axis n
uses RPDO(2n-1) = {controlword, modes of operation}, RPDO(2n) = {target position, target
velocity}, TPDO(2n-1) = {statusword, modes of operation display}, TPDO(2n) = {position
actual value, velocity actual value}; the objects of axis n are at index + 0x800 * (n-1).
Every TPDO is recorded with the kernel's receive timestamp, so durations come from the bus.
"""

from __future__ import annotations

import os
import struct
import time
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Sequence

import can
import pytest

from canopen_master import STATE_OPERATIONAL, CanopenMaster, Emcy, decode_emcy

# python-canopen, canopen/profiles/p402.py: BaseNode402.TIMEOUT_SWITCH_STATE_SINGLE = 0.4 s
STATE_TIMEOUT = float(os.environ.get("CIA402_STATE_TIMEOUT", "0.4"))

# ---------------------------------------------------------------- objects (axis 1; + 0x800 per axis)

ERROR_CODE = 0x603F
CONTROLWORD = 0x6040
STATUSWORD = 0x6041
QUICK_STOP_OPTION = 0x605A
MODES_OF_OPERATION = 0x6060
MODES_DISPLAY = 0x6061
POSITION_ACTUAL = 0x6064
VELOCITY_ACTUAL = 0x606C
TARGET_POSITION = 0x607A
PROFILE_VELOCITY = 0x6081
PROFILE_ACCELERATION = 0x6083
PROFILE_DECELERATION = 0x6084
QUICK_STOP_DECELERATION = 0x6085
TARGET_VELOCITY = 0x60FF
SUPPORTED_DRIVE_MODES = 0x6502
FOLLOWING_ERROR_WINDOW = 0x6065
FOLLOWING_ERROR_TIMEOUT = 0x6066
HOME_OFFSET = 0x607C
MAX_PROFILE_VELOCITY = 0x607F
HOMING_METHOD = 0x6098
HOMING_SPEEDS = 0x6099  # sub 1 speed during search for switch, sub 2 speed during search for zero
HOMING_ACCELERATION = 0x609A
INTERPOLATION_TIME_PERIOD = 0x60C2  # sub 1 value, sub 2 index: the period is value * 10^index s
FOLLOWING_ERROR_ACTUAL = 0x60F4
SINGLE_DEVICE_TYPE = 0x67FF
ABORT_CONNECTION_OPTION = 0x6007

# modes of operation (6060h)
MODE_PP = 1  # profile position
MODE_VL = 2  # velocity
MODE_PV = 3  # profile velocity
MODE_PT = 4  # profile torque
MODE_HM = 6  # homing
MODE_IP = 7  # interpolated position
MODE_CSP = 8  # cyclic synchronous position
MODE_CSV = 9
MODE_CST = 10

# ---------------------------------------------------------------- controlword (6040h)

# Command coding (CiA 402-2, 6040h, "Command coding" table; bits 7, 3, 2, 1, 0):
#   Shutdown                   0xxx x110   transitions 2, 6, 8
#   Switch on                  0xxx 0111   transition 3
#   Switch on + enable op.     0xxx 1111   transitions 3 + 4
#   Disable voltage            0xxx xx0x   transitions 7, 9, 10, 12
#   Quick stop                 0xxx x01x   transitions 7, 10, 11
#   Disable operation          0xxx 0111   transition 5
#   Enable operation           0xxx 1111   transitions 4, 16
#   Fault reset                0 -> 1 edge of bit 7, transition 15
CW_SHUTDOWN = 0x0006
CW_SWITCH_ON = 0x0007
CW_ENABLE_OPERATION = 0x000F
CW_DISABLE_OPERATION = 0x0007
CW_DISABLE_VOLTAGE = 0x0000
CW_QUICK_STOP = 0x000B  # enable operation with bit 2 (quick stop, low active) cleared
CW_FAULT_RESET = 0x0080

# Operation mode specific bits, profile position mode (6040h bits 4..6, 8, 9)
CW_NEW_SET_POINT = 1 << 4
CW_CHANGE_SET_IMMEDIATELY = 1 << 5
CW_RELATIVE = 1 << 6  # 0 = target position is absolute, 1 = relative
CW_HALT = 1 << 8
CW_CHANGE_ON_SET_POINT = 1 << 9

# ---------------------------------------------------------------- statusword (6041h)

SW_READY_TO_SWITCH_ON = 1 << 0
SW_SWITCHED_ON = 1 << 1
SW_OPERATION_ENABLED = 1 << 2
SW_FAULT = 1 << 3
SW_VOLTAGE_ENABLED = 1 << 4
SW_QUICK_STOP = 1 << 5  # low active: 0 = the drive reacts on a quick stop request
SW_SWITCH_ON_DISABLED = 1 << 6
SW_WARNING = 1 << 7
SW_REMOTE = 1 << 9
SW_TARGET_REACHED = 1 << 10
SW_INTERNAL_LIMIT = 1 << 11
SW_SET_POINT_ACK = 1 << 12  # pp: set-point acknowledge
SW_SPEED_ZERO = 1 << 12  # pv: speed (1 = speed is equal 0)
SW_FOLLOWING_ERROR = 1 << 13  # pp: following error; pv: max slippage error
SW_HOMING_ATTAINED = 1 << 12  # hm: homing attained
SW_HOMING_ERROR = 1 << 13  # hm: homing error
SW_DRIVE_FOLLOWS = 1 << 12  # csp, csv: drive follows the command value

# Controlword bit 4 in homing mode: homing operation start (0 -> 1 edge)
CW_HOMING_START = 1 << 4


@dataclass(frozen=True)
class State:
    """A PDS state as the statusword encodes it (CiA 402-2, 6041h, "State coding")."""

    name: str
    mask: int
    value: int

    def __call__(self, statusword: int) -> bool:
        return statusword & self.mask == self.value


NOT_READY_TO_SWITCH_ON = State("Not ready to switch on", 0x4F, 0x00)  # xxxx xxxx x0xx 0000
SWITCH_ON_DISABLED = State("Switch on disabled", 0x4F, 0x40)  # x1xx 0000
READY_TO_SWITCH_ON = State("Ready to switch on", 0x6F, 0x21)  # x01x 0001
SWITCHED_ON = State("Switched on", 0x6F, 0x23)  # x01x 0011
OPERATION_ENABLED = State("Operation enabled", 0x6F, 0x27)  # x01x 0111
QUICK_STOP_ACTIVE = State("Quick stop active", 0x6F, 0x07)  # x00x 0111
FAULT_REACTION_ACTIVE = State("Fault reaction active", 0x4F, 0x0F)  # x0xx 1111
FAULT = State("Fault", 0x4F, 0x08)  # x0xx 1000
STATES = (NOT_READY_TO_SWITCH_ON, SWITCH_ON_DISABLED, READY_TO_SWITCH_ON, SWITCHED_ON, OPERATION_ENABLED,
          QUICK_STOP_ACTIVE, FAULT_REACTION_ACTIVE, FAULT)


def state_of(statusword: int) -> Optional[State]:
    for s in STATES:
        if s(statusword):
            return s
    return None


def sw_text(statusword: int) -> str:
    """0x1237(Operation enabled|remote|target reached|bit12)."""
    s = state_of(statusword)
    names = {SW_WARNING: "warning", SW_REMOTE: "remote", SW_TARGET_REACHED: "target reached",
             SW_INTERNAL_LIMIT: "internal limit", 1 << 12: "bit12", 1 << 13: "bit13"}
    flags = [n for b, n in names.items() if statusword & b]
    return f"0x{statusword:04X}({'|'.join([s.name if s else 'no state'] + flags)})"


# ---------------------------------------------------------------- recorded frames


@dataclass
class StatusFrame:
    """TPDO(2n-1): statusword and modes of operation display."""

    t: float
    sw: int
    mode: int

    @property
    def state(self) -> Optional[State]:
        return state_of(self.sw)

    def __repr__(self):
        return f"({self.t:.3f} {sw_text(self.sw)} mode {self.mode})"


@dataclass
class MotionFrame:
    """TPDO(2n): position actual value and velocity actual value."""

    t: float
    position: int
    velocity: int

    def __repr__(self):
        return f"({self.t:.3f} p={self.position} v={self.velocity})"


def state_sequence(frames: Sequence[StatusFrame]) -> List[str]:
    """The state names in order of the frames, consecutive repeats removed."""
    out: List[str] = []
    for f in frames:
        name = f.state.name if f.state else f"0x{f.sw:04X}"
        if not out or out[-1] != name:
            out.append(name)
    return out


# ---------------------------------------------------------------- one drive (axis)


class Drive402:
    """One axis of a CiA 402 device, driven over its two RPDOs, observed through its TPDOs."""

    def __init__(self, node: "Node402", axis: int):
        self.node = node
        self.axis = axis
        k = 2 * (axis - 1)  # PDO number - 1 of this axis' first PDO
        self.rpdo_cw = (0x200, 0x300, 0x400, 0x500)[k] + node.node_id
        self.rpdo_targets = (0x200, 0x300, 0x400, 0x500)[k + 1] + node.node_id
        self.tpdo_status = (0x180, 0x280, 0x380, 0x480)[k] + node.node_id
        self.tpdo_motion = (0x180, 0x280, 0x380, 0x480)[k + 1] + node.node_id
        self.cw = 0
        self.mode = MODE_PP  # 6060h sent with every controlword (RPDO carries both)
        self.target_position = 0
        self.target_velocity = 0
        self.status_log: List[StatusFrame] = []
        self.motion_log: List[MotionFrame] = []

    # ------------------------------------------------------------ objects
    def index(self, axis1_index: int) -> int:
        """The index of an axis-1 object for this axis (CiA 402-2: + 800h per axis)."""
        return axis1_index + 0x800 * (self.axis - 1)

    @property
    def master(self) -> CanopenMaster:
        return self.node.master

    def read_u16(self, index, sub=0):
        return self.master.read_u16(self.node.node_id, self.index(index), sub)

    def read_u32(self, index, sub=0):
        return self.master.read_u32(self.node.node_id, self.index(index), sub)

    def read_i32(self, index, sub=0):
        return self.master.read_i32(self.node.node_id, self.index(index), sub)

    def read_i8(self, index, sub=0):
        data = self.master.sdo_upload(self.node.node_id, self.index(index), sub)
        assert len(data) == 1, f"0x{self.index(index):04X}: {len(data)} bytes, expected 1 (INTEGER8)"
        return struct.unpack("<b", data)[0]

    def write_u32(self, index, value, sub=0):
        self.master.write_u32(self.node.node_id, self.index(index), sub, value)

    def write_i32(self, index, value, sub=0):
        self.master.write_i32(self.node.node_id, self.index(index), sub, value)

    def write_i8(self, index, value, sub=0):
        self.master.sdo_download(self.node.node_id, self.index(index), sub, struct.pack("<b", value))

    def profile(self, velocity: Optional[int] = None, acceleration: Optional[int] = None,
                deceleration: Optional[int] = None) -> None:
        """6081h profile velocity, 6083h profile acceleration, 6084h profile deceleration (SDO)."""
        for index, value in ((PROFILE_VELOCITY, velocity), (PROFILE_ACCELERATION, acceleration),
                             (PROFILE_DECELERATION, deceleration)):
            if value is not None:
                self.write_u32(index, value)

    # ------------------------------------------------------------ RPDOs
    def controlword(self, cw: int, mode: Optional[int] = None) -> None:
        """RPDO(2n-1) = {6040h controlword U16, 6060h modes of operation I8}."""
        if mode is not None:
            self.mode = mode
        self.cw = cw & 0xFFFF
        self.master.send(self.rpdo_cw, struct.pack("<Hb", self.cw, self.mode))

    def targets(self, position: Optional[int] = None, velocity: Optional[int] = None) -> None:
        """RPDO(2n) = {607Ah target position I32, 60FFh target velocity I32}."""
        if position is not None:
            self.target_position = position
        if velocity is not None:
            self.target_velocity = velocity
        self.master.send(self.rpdo_targets, struct.pack("<ii", self.target_position, self.target_velocity))

    # ------------------------------------------------------------ observation
    def mark(self) -> int:
        """The statusword frames seen so far (everything already received is read first, so
        frames after the mark were sent after this call)."""
        self.node.drain()
        return len(self.status_log)

    def motion_mark(self) -> int:
        self.node.drain()
        return len(self.motion_log)

    @property
    def sw(self) -> int:
        """The last statusword seen in TPDO(2n-1) (event driven: sent on every change)."""
        assert self.status_log, f"axis {self.axis}: no statusword TPDO seen yet"
        return self.status_log[-1].sw

    def wait_status(self, pred: Callable[[StatusFrame], bool], timeout: float, mark: Optional[int] = None,
                    what: str = "") -> StatusFrame:
        """The first statusword frame from `mark` (default: the last one seen) satisfying pred."""
        start = max(0, self.mark() - 1) if mark is None else mark
        found: List[StatusFrame] = []

        def check():
            for f in self.status_log[start:]:
                if pred(f):
                    found.append(f)
                    return True
            return False

        if not self.node.pump(timeout, check):
            pytest.fail(f"axis {self.axis}: no statusword {what} within {timeout} s; TPDO 0x{self.tpdo_status:03X} "
                        f"frames seen: {self.status_log[start:][-12:]}", pytrace=False)
        return found[0]

    def wait_state(self, state: State, timeout: float = STATE_TIMEOUT, mark: Optional[int] = None) -> StatusFrame:
        return self.wait_status(lambda f: state(f.sw), timeout, mark, f"in state '{state.name}' "
                                f"(sw & 0x{state.mask:02X} == 0x{state.value:02X})")

    def wait_bits(self, bits: int, value: bool, timeout: float = STATE_TIMEOUT, mark: Optional[int] = None,
                  what: str = "") -> StatusFrame:
        want = bits if value else 0
        return self.wait_status(lambda f: f.sw & bits == want, timeout, mark,
                                what or f"with bits 0x{bits:04X} {'set' if value else 'clear'}")

    def command(self, cw: int, state: State, timeout: float = STATE_TIMEOUT) -> StatusFrame:
        """Send a controlword and wait for the state it commands, seen in a TPDO after it."""
        mark = self.mark()
        self.controlword(cw)
        return self.wait_state(state, timeout, mark)

    def enable(self, mode: Optional[int] = None) -> List[StatusFrame]:
        """Switch on disabled -> Ready to switch on -> Switched on -> Operation enabled
        (transitions 2, 3, 4), one state per step as CiA 402-2 figure "State machine"."""
        if mode is not None:
            self.mode = mode
        return [self.command(CW_SHUTDOWN, READY_TO_SWITCH_ON),
                self.command(CW_SWITCH_ON, SWITCHED_ON),
                self.command(CW_ENABLE_OPERATION, OPERATION_ENABLED)]

    def set_point(self, target: int, relative: bool = False, immediately: bool = False,
                  release_timeout: float = STATE_TIMEOUT) -> StatusFrame:
        """The pp set-point handshake (CiA 402-2, profile position mode, "Set-point
        transmission"): the target position is valid when bit 4 "new set-point" rises; the
        drive answers with bit 12 "set-point acknowledge"; the master clears bit 4, and the
        drive clears bit 12 when it can accept a new set-point. Returns the acknowledging
        frame. `release_timeout` is the time allowed for bit 12 to clear: a drive with a
        full set-point buffer (a buffered set-point while moving) may hold it until the
        running positioning ends."""
        mode_bits = (CW_RELATIVE if relative else 0) | (CW_CHANGE_SET_IMMEDIATELY if immediately else 0)
        base = (self.cw & ~(CW_NEW_SET_POINT | CW_RELATIVE | CW_CHANGE_SET_IMMEDIATELY)) | mode_bits
        self.targets(position=target)
        mark = self.mark()
        self.controlword(base | CW_NEW_SET_POINT)
        ack = self.wait_bits(SW_SET_POINT_ACK, True, STATE_TIMEOUT, mark, "with set-point acknowledge (bit 12)")
        mark = self.mark()
        self.controlword(base)
        self.wait_bits(SW_SET_POINT_ACK, False, release_timeout, mark, "with set-point acknowledge cleared")
        return ack

    def wait_target_reached(self, timeout: float, mark: Optional[int] = None) -> StatusFrame:
        return self.wait_bits(SW_TARGET_REACHED, True, timeout, mark, "with target reached (bit 10)")

    def motion_between(self, t0: float, t1: float) -> List[MotionFrame]:
        return [m for m in self.motion_log if t0 <= m.t <= t1]

    def wait_motion(self, pred: Callable[[MotionFrame], bool], timeout: float, mark: Optional[int] = None,
                    what: str = "") -> MotionFrame:
        start = max(0, self.motion_mark() - 1) if mark is None else mark
        found: List[MotionFrame] = []

        def check():
            for f in self.motion_log[start:]:
                if pred(f):
                    found.append(f)
                    return True
            return False

        if not self.node.pump(timeout, check):
            pytest.fail(f"axis {self.axis}: no position/velocity frame {what} within {timeout} s; TPDO "
                        f"0x{self.tpdo_motion:03X} frames seen: {self.motion_log[start:][-12:]}", pytrace=False)
        return found[0]


# ---------------------------------------------------------------- the node


class Node402:
    """A CiA 402 device's frames, sorted into its drives' logs and an EMCY list."""

    def __init__(self, master: CanopenMaster, node_id: int, axes: Sequence[int] = (1,)):
        self.master = master
        self.node_id = node_id
        self.drives: Dict[int, Drive402] = {}
        self._by_cob: Dict[int, tuple] = {}
        self.emcys: List[Emcy] = []
        self.other: List[can.Message] = []
        for n in axes:
            d = Drive402(self, n)
            self.drives[n] = d
            self._by_cob[d.tpdo_status] = (d, 0)
            self._by_cob[d.tpdo_motion] = (d, 1)

    def __getitem__(self, axis: int) -> Drive402:
        return self.drives[axis]

    def _dispatch(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_remote_frame:
            return
        data = bytes(msg.data)
        hit = self._by_cob.get(msg.arbitration_id)
        if hit is not None:
            d, k = hit
            if k == 0:
                assert len(data) == 3, f"statusword TPDO 0x{msg.arbitration_id:03X} has {len(data)} bytes: {data.hex()}"
                sw, mode = struct.unpack("<Hb", data)
                d.status_log.append(StatusFrame(msg.timestamp, sw, mode))
            else:
                assert len(data) == 8, f"position TPDO 0x{msg.arbitration_id:03X} has {len(data)} bytes: {data.hex()}"
                p, v = struct.unpack("<ii", data)
                d.motion_log.append(MotionFrame(msg.timestamp, p, v))
            return
        if msg.arbitration_id == 0x80 + self.node_id:
            self.emcys.append(decode_emcy(msg))
            return
        self.other.append(msg)

    def drain(self) -> None:
        """Record every frame already received (backlog and socket), without waiting."""
        while (msg := self.master.wait_for(lambda m: True, 0)) is not None:
            self._dispatch(msg)
        while (msg := self.master.bus.recv(timeout=0)) is not None:
            self._dispatch(msg)

    def pump(self, timeout: float, until: Optional[Callable[[], bool]] = None) -> bool:
        """Record frames for up to `timeout` s; True as soon as until() holds (checked first)."""
        if until is not None and until():
            return True
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return until is None
            msg = self.master.wait_for(lambda m: True, min(remaining, 0.05))
            if msg is not None:
                self._dispatch(msg)
            if until is not None and until():
                return True

    def wait_emcy(self, code: int, mark: int = 0, timeout: float = 2.0) -> Emcy:
        found: List[Emcy] = []

        def check():
            found[:] = [e for e in self.emcys[mark:] if e.error_code == code][:1]
            return bool(found)

        if not self.pump(timeout, check):
            pytest.fail(f"no EMCY 0x{code:04X} on 0x{0x80 + self.node_id:03X} within {timeout} s; EMCYs seen: "
                        f"{[(hex(e.error_code), e.manufacturer.hex()) for e in self.emcys[mark:]]}", pytrace=False)
        return found[0]


def boot_drive(master: CanopenMaster, start_node, tmp_path, node_id: int) -> "Node402":
    """A fresh one-axis CiA 402 node (config `profiles = ["cia402"]`), started by NMT and
    confirmed OPERATIONAL by its heartbeat, its TPDOs of that moment read."""
    path = tmp_path / "cia402.toml"
    path.write_text('axes = 1\nprofiles = ["cia402"]\n')
    start_node(node_id, ["--config", path])
    node = Node402(master, node_id, (1,))
    master.nmt_start(node_id)
    if master.wait_heartbeat(node_id, timeout=3.0, state=STATE_OPERATIONAL) != STATE_OPERATIONAL:
        pytest.fail(f"node {node_id} did not confirm NMT operational")
    node.pump(0.3)  # TPDOs sent on entering operational
    return node
