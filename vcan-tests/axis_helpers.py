"""Helpers for the test_axis_*.py vcan tests: a master that drives Horner axes over PDOs
only, and records what the node reports (TPDO1 status + motor position, TPDO2 motor +
encoder position, TPDO3 velocity + phase, EMCY) with the kernel's receive timestamps.

Register model (SPM30 chapter 3, STP100 chapter 4): command bits %Q1..%Q16 are bits 0..15
of the command word (RPDO1), status bits %I1..%I16 bits 0..15 of the status word (TPDO1).
Commands are OFF->ON edges: `Axis.command` sends the bit, then the word without it.

STPCALC (SPM30 appendix B) is reimplemented here from the manual's formulas, so the ramp
times the tests expect come from the manual and not from the node's code.
"""

from __future__ import annotations

import struct
import threading
import time
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional

import can
import pytest

from canopen_master import STATE_OPERATIONAL, decode_emcy
from conftest import open_bus

NODE = 7

# %I1..%I16 (SPM30 3.1)
E_STOP, LOWER, UPPER, ILLEGAL, STALLED = 0x0001, 0x0002, 0x0004, 0x0008, 0x0010
WATCHDOG = 0x0080
ERRORS = 0x00FF
VALID, RESUMABLE, AT_HOME = 0x0100, 0x0200, 0x1000
ACCEL, DECEL, MOVING = 0x2000, 0x4000, 0x8000

# %Q1..%Q16 (SPM30 3.2; %Q11 Move Indexed and %Q12 Repeat Move from STP113 / STP100)
Q = {name: 1 << i for i, name in enumerate(
    ["sel1", "sel2", "sel3", "home_up", "home_down", "jog_up", "jog_down", "rel", "abs", "resume",
     "indexed", "repeat", "set", "clear", "stop", "estop"])}

# Motion phase of TPDO3 (0x2n08): 0 idle, 1 accelerating, 2 running, 3 decelerating, 4 base.
PH_IDLE, PH_ACC, PH_RUN, PH_DEC, PH_BASE = 0, 1, 2, 3, 4

EMCY_AXIS1 = 0xFF01
EMCY_HEARTBEAT = 0x8130

# The simulated machine (0x5000 + 0x100 * motor).
SIM_SWITCHES, SIM_ENCODER, SIM_FAULTS, SIM_MECH = 0x5000, 0x5001, 0x5002, 0x5003
SIM_ESTOP = 0x5F00


def status_text(s: int) -> str:
    names = ["ESTOP", "LOWER", "UPPER", "ILLEGAL", "STALLED", "I6", "I7", "WATCHDOG", "VALID", "RESUMABLE",
             "AX2", "AX3", "HOME", "ACC", "DEC", "MOVING"]
    on = [n for i, n in enumerate(names) if s >> i & 1]
    return f"0x{s:04X}({'|'.join(on) or '-'})"


# ---------------------------------------------------------------- STPCALC (appendix B)


@dataclass
class Stpcalc:
    aq3: int
    aq4: int
    aq5: int
    aq6: int
    aq7: int = 0

    def _z(self, ms: int) -> int:  # B1.3.1 / B1.3.2: rounded up to the nearest integer
        return -(-ms * 24576 // ((self.aq5 - self.aq4) * 5))

    @property
    def z_a(self) -> int:
        return self._z(self.aq6)

    @property
    def z_d(self) -> int:
        # 3.4.6: a deceleration time of 0 means "the same as the acceleration time".
        return self._z(self.aq7 or self.aq6)

    @property
    def time_a_ms(self) -> float:  # B1.3.11
        return (self.aq5 - self.aq4) * self.z_a * 5 / 24576

    @property
    def time_d_ms(self) -> float:  # B1.3.13
        return (self.aq5 - self.aq4) * self.z_d * 5 / 24576

    @property
    def pulse_a(self) -> float:  # B1.3.7
        return (self.aq5 - self.aq4) * (self.aq5 + self.aq4 + 1) * self.z_a / (16384 * self.aq3)

    @property
    def pulse_d(self) -> float:  # B1.3.9
        return (self.aq5 - self.aq4) * (self.aq5 + self.aq4 + 1) * self.z_d / (16384 * self.aq3)

    @property
    def vel_b(self) -> float:  # B1.3.4
        return self.aq4 * 600 / self.aq3

    @property
    def vel_r(self) -> float:  # 3.4.4 (B1.3.5 misprints AQ4)
        return self.aq5 * 600 / self.aq3

    def move_time_ms(self, total: int) -> float:  # B1.3.15, trapezoidal moves
        run = total - self.pulse_a - self.pulse_d
        assert run >= 0, "triangular move: STPCALC's time is not a physical profile"
        return self.time_a_ms + run * 1000 / self.vel_r + self.time_d_ms


# ---------------------------------------------------------------- recorded frames


@dataclass
class StatusFrame:
    t: float
    status: int
    position: int

    def __repr__(self):
        return f"({self.t:.3f} {status_text(self.status)} @{self.position})"


@dataclass
class PositionFrame:
    t: float
    motor: int
    encoder: int


@dataclass
class VelocityFrame:
    t: float
    velocity: int
    phase: int


class Axis:
    """One axis driven over its four RPDOs and observed through its TPDOs."""

    def __init__(self, link: "NodeLink", number: int, rpdo: List[int], tpdo: List[int]):
        self.link = link
        self.number = number  # 1-based
        self.rpdo = rpdo      # COB-IDs of RPDO1..4 of this axis
        self.tpdo = tpdo      # COB-IDs of TPDO1..3 of this axis
        self.held = 0         # level bits kept on (%Q6/%Q7 jog, %Q12 repeat)
        self.dest = 0
        self.status_log: List[StatusFrame] = []
        self.position_log: List[PositionFrame] = []
        self.velocity_log: List[VelocityFrame] = []

    # ------------------------------------------------------------ object indices
    def obj(self, offset: int) -> int:
        return 0x2000 + 0x100 * (self.number - 1) + offset

    def sim(self, offset: int) -> int:
        return offset + 0x100 * (self.number - 1)

    # ------------------------------------------------------------ RPDOs
    def rpdo1(self, bits: int, dest: Optional[int] = None) -> None:
        if dest is not None:
            self.dest = dest
        self.link.master.send(self.rpdo[0], struct.pack("<Hi", bits & 0xFFFF, self.dest))

    def command(self, name: str, dest: Optional[int] = None) -> None:
        """An OFF->ON edge of one %Q (level bits held stay on), then OFF again."""
        self.rpdo1(self.held | Q[name], dest)
        self.rpdo1(self.held)

    def hold(self, *names: str, dest: Optional[int] = None) -> None:
        """Set the level bits (jog, repeat) to exactly `names`."""
        self.held = 0
        for n in names:
            self.held |= Q[n]
        self.rpdo1(self.held, dest)

    def profile(self, aq3: int, aq4: int, aq5: int, aq6: int) -> None:
        self.link.master.send(self.rpdo[1], struct.pack("<HHHH", aq3, aq4, aq5, aq6))

    def decel_and_index(self, aq7: int, aq10: int = 0, aq8: int = 0) -> None:
        self.link.master.send(self.rpdo[2], struct.pack("<HHI", aq7, aq10, aq8))

    def window(self, open_: int, close: int) -> None:
        self.link.master.send(self.rpdo[3], struct.pack("<II", open_, close))

    def set_profile(self, calc: Stpcalc, aq10: int = 0, aq8: int = 0) -> None:
        self.profile(calc.aq3, calc.aq4, calc.aq5, calc.aq6)
        self.decel_and_index(calc.aq7, aq10, aq8)

    # ------------------------------------------------------------ observation
    @property
    def status(self) -> int:
        """The last status seen in TPDO1 (the node sends it on every change)."""
        assert self.status_log, f"axis {self.number}: no TPDO1 seen yet"
        return self.status_log[-1].status

    @property
    def position(self) -> int:
        return self.status_log[-1].position

    def mark(self) -> int:
        return len(self.status_log)

    def since(self, mark: int) -> List[StatusFrame]:
        return self.status_log[mark:]

    def wait_status(self, pred: Callable[[int], bool], timeout: float = 5.0, mark: Optional[int] = None,
                    what: str = "") -> StatusFrame:
        """The first TPDO1 (from `mark`, default: the last one seen) whose status satisfies pred."""
        start = max(0, self.mark() - 1) if mark is None else mark
        found: List[StatusFrame] = []

        def check():
            for f in self.status_log[start:]:
                if pred(f.status):
                    found.append(f)
                    return True
            return False

        if not self.link.pump(timeout, check):
            pytest.fail(f"axis {self.number}: no status {what} within {timeout} s; TPDO1 seen: "
                        f"{self.status_log[start:][-12:]}")
        return found[0]

    def wait_stopped(self, mark: int, timeout: float = 30.0) -> List[StatusFrame]:
        """TPDO1s from `mark` up to the first standstill after motion (MOVING on, then off)."""
        def done():
            moved = False
            for f in self.status_log[mark:]:
                moved |= bool(f.status & MOVING)
                if moved and not f.status & MOVING:
                    return True
            return False

        if not self.link.pump(timeout, done):
            pytest.fail(f"axis {self.number}: did not move and stop within {timeout} s; TPDO1 seen: "
                        f"{self.status_log[mark:][-12:]}")
        out = []
        moved = False
        for f in self.status_log[mark:]:
            out.append(f)
            moved |= bool(f.status & MOVING)
            if moved and not f.status & MOVING:
                break
        return out

    def move(self, name: str, dest: Optional[int] = None, timeout: float = 30.0) -> List[StatusFrame]:
        """Issue a motion command and return the TPDO1s up to standstill."""
        mark = self.mark()
        self.command(name, dest)
        return self.wait_stopped(mark, timeout)

    def quiet(self, duration: float) -> List[StatusFrame]:
        """Let `duration` seconds pass while recording; the TPDO1s seen meanwhile."""
        mark = self.mark()
        self.link.pump(duration)
        return self.since(mark)

    def velocities_between(self, t0: float, t1: float) -> List[VelocityFrame]:
        return [v for v in self.velocity_log if t0 <= v.t <= t1]

    def positions_between(self, t0: float, t1: float) -> List[PositionFrame]:
        return [p for p in self.position_log if t0 <= p.t <= t1]

    def mechanical(self) -> int:
        """The simulated machine's load position (SDO 0x5n03: reading the wiring, not driving)."""
        return self.link.master.read_i32(self.link.node, self.sim(SIM_MECH))


def sequence(frames: List[StatusFrame], mask: int = 0xFFFF) -> List[int]:
    """The statuses (masked) in order, consecutive repeats removed."""
    out: List[int] = []
    for f in frames:
        s = f.status & mask
        if not out or out[-1] != s:
            out.append(s)
    return out


def seq_text(seq: List[int]) -> str:
    return " -> ".join(status_text(s) for s in seq)


def bit_intervals(frames: List[StatusFrame], bit: int) -> List[tuple]:
    """(t_on, t_off) for every period in which `bit` was on (t_off None if still on)."""
    out = []
    on = None
    for f in frames:
        if f.status & bit and on is None:
            on = f.t
        elif not f.status & bit and on is not None:
            out.append((on, f.t))
            on = None
    if on is not None:
        out.append((on, None))
    return out


def assert_duration(label: str, interval: tuple, expect_ms: float, tol_ms: float = 40.0) -> float:
    t_on, t_off = interval
    assert t_off is not None, f"{label}: the bit never went off"
    got = (t_off - t_on) * 1000
    assert abs(got - expect_ms) <= tol_ms, f"{label}: {got:.1f} ms observed, STPCALC {expect_ms:.2f} ms (±{tol_ms})"
    return got


class NodeLink:
    """Everything one node sends, sorted by COB-ID into its axes' logs and an EMCY list."""

    def __init__(self, master, node: int):
        self.master = master
        self.node = node
        self.axes: Dict[int, Axis] = {}
        self._by_cob: Dict[int, tuple] = {}
        self.emcys: list = []
        self.other: List[can.Message] = []

    def add_axis(self, number: int, rpdo: Optional[List[int]] = None, tpdo: Optional[List[int]] = None) -> Axis:
        if rpdo is None:
            rpdo = [0x200 + self.node, 0x300 + self.node, 0x400 + self.node, 0x500 + self.node]
        if tpdo is None:
            tpdo = [0x180 + self.node, 0x280 + self.node, 0x380 + self.node]
        ax = Axis(self, number, rpdo, tpdo)
        self.axes[number] = ax
        for k, cob in enumerate(tpdo):
            self._by_cob[cob] = (ax, k)
        return ax

    def _dispatch(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_remote_frame:
            return
        cob = msg.arbitration_id
        data = bytes(msg.data)
        if cob in self._by_cob:
            ax, k = self._by_cob[cob]
            if k == 0:
                assert len(data) == 6, f"TPDO1 of axis {ax.number} has {len(data)} bytes: {data.hex()}"
                s, p = struct.unpack("<Hi", data)
                ax.status_log.append(StatusFrame(msg.timestamp, s, p))
            elif k == 1:
                assert len(data) == 8, f"TPDO2 of axis {ax.number} has {len(data)} bytes: {data.hex()}"
                m, e = struct.unpack("<ii", data)
                ax.position_log.append(PositionFrame(msg.timestamp, m, e))
            elif k == 2:
                assert len(data) == 5, f"TPDO3 of axis {ax.number} has {len(data)} bytes: {data.hex()}"
                v, ph = struct.unpack("<iB", data)
                ax.velocity_log.append(VelocityFrame(msg.timestamp, v, ph))
            return
        if cob == 0x80 + self.node:
            self.emcys.append(decode_emcy(msg))
            return
        if cob == 0x700 + self.node:
            return  # our heartbeat
        self.other.append(msg)

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

    def emcy_mark(self) -> int:
        return len(self.emcys)

    def wait_emcy(self, code: int, mark: int = 0, timeout: float = 3.0):
        found = []

        def check():
            for e in self.emcys[mark:]:
                if e.error_code == code:
                    found.append(e)
                    return True
            return False

        if not self.pump(timeout, check):
            pytest.fail(f"no EMCY 0x{code:04X} from node {self.node} within {timeout} s; EMCYs seen: "
                        f"{[(hex(e.error_code), e.manufacturer.hex()) for e in self.emcys[mark:]]}")
        return found[0]

    def emcy_codes(self, mark: int = 0) -> List[int]:
        return [e.error_code for e in self.emcys[mark:]]


# ---------------------------------------------------------------- heartbeat producer


class HeartbeatSender:
    """The test's own heartbeat (node 0x7F, operational) every `period` s, on its own socket."""

    def __init__(self, node: int = 0x7F, period: float = 0.1):
        self.node = node
        self.period = period
        self._stop = threading.Event()
        self._bus = open_bus()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.sent = 0
        self.last_sent = 0.0

    def _run(self):
        msg = can.Message(arbitration_id=0x700 + self.node, data=bytes([STATE_OPERATIONAL]), is_extended_id=False)
        while not self._stop.is_set():
            try:
                self._bus.send(msg, timeout=0.5)
                self.sent += 1
                self.last_sent = time.time()  # the clock of the frames' timestamps
            except can.CanError:
                pass
            self._stop.wait(self.period)

    def start(self) -> "HeartbeatSender":
        self._thread.start()
        return self

    def stop(self) -> float:
        """Stop sending; returns the monotonic time of the stop."""
        self._stop.set()
        self._thread.join(2.0)
        return time.monotonic()

    def close(self):
        if not self._stop.is_set():
            self.stop()
        self._bus.shutdown()


# ---------------------------------------------------------------- fixtures

# Profiles. SLOW is the brief's STPCALC example (1 pulse/s units: 100..1000 pulses/s, 500 ms);
# FAST keeps tests short (10 pulses/s units: 200..4000 pulses/s, 100 ms).
SLOW = Stpcalc(600, 100, 1000, 500, 300)
FAST = Stpcalc(60, 20, 400, 100, 0)


def boot(master, start_node, node: int = NODE, extra_args=()) -> NodeLink:
    """Start a node, put it in operational and return its link with axis 1 registered and
    the TPDOs sent on entering operational already recorded."""
    start_node(node, extra_args)
    link = NodeLink(master, node)
    link.add_axis(1)
    master.nmt_start(node)
    if master.wait_heartbeat(node, timeout=3.0, state=STATE_OPERATIONAL) != STATE_OPERATIONAL:
        pytest.fail(f"node {node} did not confirm operational")
    ax = link.axes[1]
    link.pump(3.0, lambda: bool(ax.status_log and ax.position_log and ax.velocity_log))
    return link


def clear_and_profile(ax: Axis, calc: Stpcalc = FAST) -> None:
    """The first command after power-up: Clear Errors; then the profile words."""
    ax.set_profile(calc)
    mark = ax.mark()
    ax.command("clear")
    ax.wait_status(lambda s: not s & ERRORS, 3.0, mark, "without errors after Clear Errors")


@pytest.fixture
def link(master, start_node) -> NodeLink:
    """Node 7 in operational; axis 1 cleared, FAST profile sent."""
    lk = boot(master, start_node)
    clear_and_profile(lk.axes[1])
    return lk


@pytest.fixture
def ax(link) -> Axis:
    return link.axes[1]


def set_position(ax: Axis, value: int) -> None:
    """%Q13 with DESTINATION = value; waits for VALID (TPDO1) and the position (TPDO2, which
    streams every change of the motor position; TPDO1 is sent only when the status changes)."""
    ax.command("set", value)
    ax.link.pump(3.0, lambda: bool(ax.status_log[-1].status & VALID) and ax.position_log[-1].motor == value)
    assert ax.status & VALID, f"no VALID after Set Current Position: {ax.status_log[-5:]}"
    assert ax.position_log[-1].motor == value, \
        f"TPDO2 motor position {ax.position_log[-1].motor} after Set Current Position {value}"


__all__ = [n for n in dir() if not n.startswith("_")]


# ---------------------------------------------------------------- the ramp down from a velocity


def ramp_steps_from(calc: Stpcalc, velocity: float) -> float:
    """The steps a deceleration of `calc` takes from `velocity` (steps/s) down to the base
    velocity, on the module's quantised ramp (SPM30 appendix B): the velocity falls one unit
    of 600/%AQ3 pulses/s every Z_D ticks of 4.9152 MHz, so from level L (velocity / unit) to
    %AQ4 it makes sum(k, k = %AQ4..L) * 600/%AQ3 * Z_D / 4.9152e6 steps -- B1.3.9 with L in
    place of %AQ5. 0 at or below the base velocity."""
    level = velocity * calc.aq3 / 600
    if level <= calc.aq4:
        return 0.0
    return (level - calc.aq4) * (level + calc.aq4 + 1) * calc.z_d / (16384 * calc.aq3)
