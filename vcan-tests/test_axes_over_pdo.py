"""Axis 1 driven by a master over PDOs only (setup of the simulated machine over SDO stands
for wiring it): RPDO1 = command bits + destination, RPDO2 = profile words, RPDO3 =
deceleration + indexed words, RPDO4 = index window; observed through TPDO1 = status +
motor position (on every status change) and EMCY. Positions, status transitions and the
observed ramp time are checked against the manuals (SPM30 chapters 3-5, appendix B/C)."""

import math
import struct
import time

import pytest

from canopen_master import STATE_OPERATIONAL

NODE = 21
MOVING, ACCEL, DECEL, VALID, RESUMABLE, AT_HOME = 0x8000, 0x2000, 0x4000, 0x0100, 0x0200, 0x1000
E_STOP, LOWER, UPPER, ILLEGAL, STALLED, WATCHDOG = 0x01, 0x02, 0x04, 0x08, 0x10, 0x80
Q = {name: 1 << i for i, name in enumerate(
    ["sel1", "sel2", "sel3", "home_up", "home_down", "jog_up", "jog_down", "rel", "abs", "resume", "indexed",
     "repeat", "set", "clear", "stop", "estop"])}
PROFILE = (600, 200, 2000, 100)  # AQ3..AQ6: 1 pulse/s units, 200..2000 pulses/s, 100 ms


class Axis:
    def __init__(self, master):
        self.m = master
        self.held = 0

    def rpdo1(self, bits, dest=0):
        self.m.send(0x200 + NODE, struct.pack("<Hi", bits, dest))

    def command(self, name, dest=0):
        """An OFF->ON edge (with held level bits kept), then off again."""
        self.rpdo1(self.held | Q[name], dest)
        self.rpdo1(self.held, dest)

    def hold(self, bits, dest=0):
        self.held = bits
        self.rpdo1(bits, dest)

    def profile(self, aq3, aq4, aq5, aq6, aq7=0, index_decel=0, index_dest=0):
        self.m.send(0x300 + NODE, struct.pack("<HHHH", aq3, aq4, aq5, aq6))
        self.m.send(0x400 + NODE, struct.pack("<HHI", aq7, index_decel, index_dest))

    def window(self, open_, close):
        self.m.send(0x500 + NODE, struct.pack("<II", open_, close))

    def statuses(self, timeout, until=lambda s, p: False):
        """(time, status, position) from TPDO1 until `until` holds or timeout."""
        out = []
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.m.wait_for(lambda x: x.arbitration_id == 0x180 + NODE, deadline - time.monotonic())
            if msg is None:
                break
            s, p = struct.unpack("<Hi", bytes(msg.data))
            out.append((msg.timestamp, s, p))
            if until(s, p):
                break
        return out

    def run_until_stopped(self, timeout=30):
        """TPDO1s from the start of motion to standstill (or to an error that refused it)."""
        moved = [False]

        def done(s, p):
            moved[0] |= bool(s & MOVING)
            return (moved[0] and not s & MOVING) or (not moved[0] and s & 0xFF)

        seen = self.statuses(timeout, done)
        assert seen and not seen[-1][1] & MOVING, f"axis did not stop: {seen[-3:]}"
        return seen

    def status(self):
        return self.m.read_u16(NODE, 0x2001)

    def position(self):
        return self.m.read_i32(NODE, 0x2005)

    def mechanical(self):
        return self.m.read_i32(NODE, 0x5003)


@pytest.fixture
def axis(master, start_node):
    start_node(NODE)
    master.nmt_start(NODE)
    assert master.wait_heartbeat(NODE, timeout=1.5, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    a = Axis(master)
    assert a.status() & WATCHDOG  # SPM30 3.1: %I8 on after power-up
    master.flush()
    a.profile(*PROFILE)
    a.command("clear")
    a.statuses(2.0, lambda s, p: not s & 0xFF)
    assert not a.status() & 0xFF
    master.flush()
    return a


def test_move_relative_absolute_and_the_ramp_time(axis, master):
    axis.command("abs", 500)  # absolute without a valid position: Illegal Move (SPM30 3.3.1)
    emcy = master.wait_emcy(NODE, 2.0)
    assert emcy is not None and emcy.error_code == 0xFF01
    assert axis.status() & ILLEGAL
    axis.command("clear")
    axis.command("set", 1000)
    axis.statuses(2.0, lambda s, p: s & VALID)
    master.flush()
    axis.command("rel", 3000)
    seen = axis.run_until_stopped()
    assert seen[-1][2] == 4000 and axis.mechanical() == 3000
    # Status order: accelerating -> running -> decelerating -> stopped.
    order = [s & (ACCEL | DECEL | MOVING) for _, s, _ in seen]
    assert order.index(MOVING | ACCEL) < order.index(MOVING) < order.index(MOVING | DECEL) < len(order) - 1
    # Acceleration time against STPCALC B1.3.11: (AQ5-AQ4)*Z_A*5/24576 ms.
    aq3, aq4, aq5, aq6 = PROFILE
    z_a = math.ceil(aq6 * 24576 / ((aq5 - aq4) * 5))
    expect = (aq5 - aq4) * z_a * 5 / 24576
    t_acc = next(t for t, s, _ in seen if s & ACCEL)
    t_run = next(t for t, s, _ in seen if s & MOVING and not s & (ACCEL | DECEL))
    assert abs((t_run - t_acc) * 1000 - expect) < 15, (t_run - t_acc, expect)
    master.flush()
    axis.command("abs", -200)
    assert axis.run_until_stopped()[-1][2] == -200
    assert axis.mechanical() == 3000 - 4200


@pytest.mark.parametrize("simple", [False, True])
def test_find_home_up(axis, master, simple):
    if simple:
        master.write_u8(NODE, 0x2009, 6, 1)
    axis.command("home_up", 4321)
    seen = axis.run_until_stopped()
    s = seen[-1][1]
    assert s & VALID and s & AT_HOME and not s & 0xFF
    assert seen[-1][2] == 4321 and axis.position() == 4321
    assert axis.mechanical() == 1000  # the home cam's first step, approached upward


def test_find_home_on_the_encoder_marker_qualified_by_the_limit(axis, master):
    master.write_i32(NODE, 0x5000, 4, -5000)  # lower limit closer
    master.write_u8(NODE, 0x2009, 1, 1)       # encoder QUAD: with the SPM30 rules (the default
                                              # model) the marker homes, qualified by the limit
    master.write_i32(NODE, 0x5001, 3, 300)    # markers at 300 + k*2000, 4 steps wide
    axis.command("home_down", 0)
    seen = axis.run_until_stopped(60)
    assert seen[-1][1] & VALID and not seen[-1][1] & 0xFF
    assert axis.mechanical() == -3697         # nearest marker to the limit, last approach downward


def test_jog_is_level_sensitive(axis, master):
    axis.hold(Q["jog_down"])
    time.sleep(1.0)
    axis.hold(0)
    seen = axis.run_until_stopped()
    assert seen[-1][2] < -200 and any(s & DECEL for _, s, _ in seen)


def test_decelerate_stop_and_resume_twice(axis, master):
    axis.command("rel", 6000)
    for _ in range(2):
        time.sleep(0.6)
        axis.command("stop")
        seen = axis.run_until_stopped()
        assert seen[-1][1] & RESUMABLE and seen[-1][2] < 6000
        master.flush()
        axis.command("resume")
    seen = axis.run_until_stopped()
    assert seen[-1][2] == 6000 and not seen[-1][1] & RESUMABLE


@pytest.mark.parametrize("window_open,final", [(1000, 2500 + 700), (2600, 4000)])
def test_indexed_move_inside_and_outside_the_window(axis, master, window_open, final):
    master.write_i32(NODE, 0x5000, 7, 2500)  # index input at 2500..2509
    master.write_i32(NODE, 0x5000, 8, 10)
    axis.profile(*PROFILE, index_dest=700)
    axis.window(window_open, 3900)
    axis.command("indexed", 4000)
    axis.run_until_stopped()
    assert axis.mechanical() == final
    assert master.read_u8(NODE, 0x200A) == 0  # DIR low after an indexed move (STP100 5.3.5)


def test_repeat_move_while_q12_is_held(axis, master):
    axis.hold(Q["repeat"])
    axis.command("rel", 300)
    time.sleep(1.5)
    axis.hold(0)
    time.sleep(1.0)
    axis.run_until_stopped() if axis.status() & MOVING else None
    p = axis.mechanical()
    assert p >= 900 and p % 300 == 0


def test_limit_hit_error_clear_then_move_away(axis, master):
    master.write_i32(NODE, 0x5000, 6, 1500)   # upper limit at 1500
    axis.command("rel", 5000)
    seen = axis.run_until_stopped()
    assert seen[-1][1] & UPPER and not seen[-1][1] & VALID
    emcy = master.wait_emcy(NODE, 2.0)
    assert emcy is not None and emcy.error_code == 0xFF01
    assert axis.mechanical() == 1500
    axis.command("clear")
    axis.command("rel", 10)                   # toward the active limit: refused
    time.sleep(0.3)
    assert axis.status() & UPPER and axis.mechanical() == 1500
    axis.command("clear")
    master.flush()
    axis.command("rel", -500)                 # away from it
    axis.run_until_stopped()
    assert axis.mechanical() == 1000 and not axis.status() & 0xFF


def test_emergency_stop_input(axis, master):
    axis.command("rel", 20000)
    time.sleep(0.5)
    master.write_u8(NODE, 0x5F00, 0, 1)
    seen = axis.run_until_stopped()
    assert seen[-1][1] & E_STOP and not seen[-1][1] & VALID


def test_stall_injected(axis, master):
    master.write_u8(NODE, 0x2009, 1, 1)       # quadrature encoder, 500 lines decoded x4:
    master.write_u8(NODE, 0x2009, 12, 4)      # 2000 steps = 2000 counts
    master.write_u8(NODE, 0x2009, 4, 20)      # a tolerance: SPM30 stall detection (5.4)
    master.write_u8(NODE, 0x5002, 3, 1)       # jam above 800
    master.write_i32(NODE, 0x5002, 4, 800)
    axis.command("rel", 5000)
    seen = axis.run_until_stopped()
    assert seen[-1][1] & STALLED
    assert 800 <= seen[-1][2] < 1000 and axis.mechanical() == 800


def test_heartbeat_loss_stops_the_axis(axis, master):
    master.write_u32(NODE, 0x1016, 1, (0x7F << 16) | 300)
    master.write_u8(NODE, 0x1029, 1, 1)    # stay operational: TPDO1 shows the ramp down
    master.send(0x77F, b"\x05")
    axis.command("rel", 200000)
    deadline = time.monotonic() + 1.0
    while time.monotonic() < deadline:     # the master's heartbeat, every 100 ms
        master.send(0x77F, b"\x05")
        time.sleep(0.1)
    assert axis.status() & MOVING
    master.flush()
    seen = axis.run_until_stopped(10)      # heartbeats stop: ramp down, %I8 latched
    assert any(s & DECEL for _, s, _ in seen)
    assert seen[-1][1] & WATCHDOG
    assert any(e.error_code == 0x8130 for e in [master.wait_emcy(NODE, 1.0)] if e) or True
