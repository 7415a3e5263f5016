"""The master lost in the middle of a move, and a stop sent during the ramp that follows
(issue 14). The heartbeat of the master (node 0x7F, consumed through 0x1016) stops; the
node sends EMCY 0x8130 and ramps the moving axis down with its deceleration (README
"Communication errors and NMT states"). During that ramp a master -- the same one back on
the bus, or a second one -- sends a stop:

(%I13 at home follows the simulated home switch wherever the axis stops; it is not checked.)

- %Q16 Immediate Stop: SPM30 chapter 4 gives it "Status Bits Required: None", so it is
  obeyed in every state, and "the current axis will stop as quickly as possible"; the
  axis must stand after far fewer steps than the ramp still had to go, and %I9 (position
  valid) goes off because the axis was moving (SPM30 3.3.1).
- %Q15 Decelerate and Stop: "decelerate until it reaches the BASE VELOCITY and then it
  will stop" -- the ramp already does that, so the axis stops where the ramp ends, the
  position stays valid, and %I10 stays off ("resumable ... unless an error occurred": %I8
  is latched).

The ramp's remaining steps come from the profile words and STPCALC's quantised ramp (SPM30
appendix B), never from a run. With 0x1029:1 = 1 the node stays operational and the stop
goes over the axis' RPDO1; with CiA 301's default 0x1029:1 = 0 it goes pre-operational
(no PDOs), and the stop is an SDO write of the command word 0x2000.
"""

from __future__ import annotations

import struct
import time

import can
import pytest

from axis_helpers import (
    AT_HOME, DECEL, MOVING, NODE, Q, RESUMABLE, VALID, WATCHDOG, HeartbeatSender, Stpcalc, ax, link, ramp_steps_from,
    set_position, status_text,
)
from canopen_master import STATE_PREOPERATIONAL
from conftest import open_bus

_ = (link, ax)  # fixtures

MASTER = 0x7F
HB_TIMEOUT_MS = 300
# 10 steps/s per unit: base 200 steps/s, running 4000 steps/s, 100 ms up, 1200 ms down
# (SPM30 3.4.6: the maximum useful %AQ7 here is (400 - 20) / 0.3 = 1266 ms).
RAMP = Stpcalc(60, 20, 400, 100, 1200)
# "Far below what the ramp would have taken": at most a quarter of the steps it had left.
FAR_BELOW = 4
# The stop must come while the ramp still has this many steps to go, or it tests nothing.
MEANINGFUL = 1000
EMCY_HEARTBEAT = 0x8130
ERROR_REGISTER_GENERIC, ERROR_REGISTER_COMMUNICATION = 0x01, 0x10
CMD, STATUS, MOTOR, VELOCITY = 0x2000, 0x2001, 0x2005, 0x2007
SIM_MECH = 0x5003


def watch_the_master(master, error_behaviour: int) -> HeartbeatSender:
    hb = HeartbeatSender(MASTER, 0.1).start()
    master.write_u32(NODE, 0x1016, 1, (MASTER << 16) | HB_TIMEOUT_MS)
    master.write_u8(NODE, 0x1029, 1, error_behaviour)
    time.sleep(0.5)
    return hb


def assert_heartbeat_emcy(link, mark: int) -> None:
    """CiA 301 EMCY: error code 0x8130 (life guard or heartbeat error), error register
    (0x1001) with bit 0 (generic: set whenever an error is signalled) and bit 4
    (communication error)."""
    em = link.wait_emcy(EMCY_HEARTBEAT, mark)
    want = ERROR_REGISTER_GENERIC | ERROR_REGISTER_COMMUNICATION
    assert em.error_register & want == want, f"EMCY 0x8130 with error register 0x{em.error_register:02X}"


def run_at_speed(ax) -> int:
    """Set position 0, start a long relative move, wait for the running velocity; the mark
    of the status log before the move."""
    set_position(ax, 0)
    mark = ax.mark()
    ax.command("rel", 200_000)  # 50 s at 4000 steps/s: only a stop ends it here
    ax.wait_status(lambda s: s == MOVING | VALID, 5.0, mark, "running")
    ax.link.pump(3.0, lambda: bool(ax.velocity_log) and ax.velocity_log[-1].velocity == RAMP.vel_r)
    assert ax.velocity_log[-1].velocity == RAMP.vel_r, f"not at {RAMP.vel_r} steps/s: {ax.velocity_log[-3:]}"
    return mark


def at(log, t: float):
    """The last frame of a position or velocity log received at or before t."""
    before = [f for f in log if f.t <= t]
    assert before, f"nothing recorded before {t}"
    return before[-1]


def first_after(log, t: float):
    """The first frame of a position or velocity log received after t."""
    after = [f for f in log if f.t > t]
    assert after, f"nothing recorded after {t}"
    return after[0]


def send_rpdo1_from_a_second_master(bits: int, dest: int) -> float:
    """The command word as a second master on the bus sends it (its own socket); the wall
    clock time of the sending (the clock of the frames' kernel timestamps)."""
    second = open_bus()
    try:
        t = time.time()
        for word in (bits, 0):
            second.send(can.Message(arbitration_id=0x200 + NODE, data=struct.pack("<Hi", word, dest),
                                    is_extended_id=False), timeout=0.5)
        return t
    finally:
        second.shutdown()


@pytest.mark.parametrize("stop", ["estop", "stop"], ids=["immediate-stop-Q16", "decelerate-and-stop-Q15"])
def test_a_stop_during_the_lost_master_ramp_over_rpdo(link, ax, master, stop):
    ax.set_profile(RAMP)
    hb = watch_the_master(master, 1)  # 0x1029:1 = 1: stays operational, PDOs keep going
    try:
        mark = run_at_speed(ax)
        emark = link.emcy_mark()
        hb.stop()
        dec = ax.wait_status(lambda s: bool(s & DECEL), 2.0, mark, "decelerating after the master was lost")
        assert dec.status & WATCHDOG, f"ramp without %I8 latched: {status_text(dec.status)}"
        t_stop = send_rpdo1_from_a_second_master(Q[stop], ax.dest)
        frames = ax.wait_stopped(mark, 10.0)
        link.pump(0.3)
        final = frames[-1]
        # The ramp would end STPCALC's deceleration pulses after it began; when the stop was
        # sent the axis stood at most where the first position after it says, so the ramp
        # had at least `left` steps to go; it has made `after` steps since the last
        # position before the stop (an upper bound of the steps the stop let through).
        end = dec.position + RAMP.pulse_d
        before, behind = at(ax.position_log, t_stop).motor, first_after(ax.position_log, t_stop).motor
        left, after = end - behind, final.position - before
        print(f"\n{stop}: the ramp began at {dec.position}, STPCALC ends it at {end:.0f}; the stop was sent "
              f"between {before} and {behind} ({left:.0f} steps of ramp left); stood at {final.position}, "
              f"{after} steps after")
        assert left >= MEANINGFUL, f"the stop came too late in the ramp ({left:.0f} steps left) to test it"
        assert_heartbeat_emcy(link, emark)
        if stop == "estop":
            assert after <= left / FAR_BELOW, f"{after} steps after Immediate Stop; the ramp had {left:.0f} left"
            assert final.status & ~AT_HOME == WATCHDOG, f"after Immediate Stop: {status_text(final.status)} (want %I8 only)"
        else:
            assert abs(final.position - end) <= 20, f"stood at {final.position}, the ramp ends at {end:.0f}"
            assert final.status & ~AT_HOME == VALID | WATCHDOG and not final.status & RESUMABLE, status_text(final.status)
        # It stands, for longer than the rest of the ramp would have lasted.
        stood = ax.mechanical()
        assert stood == final.position
        link.pump(RAMP.time_d_ms / 1000)
        assert ax.mechanical() == stood and ax.position_log[-1].motor == stood
    finally:
        hb.close()


def poll_status(master, pred, timeout: float, what: str) -> int:
    deadline = time.monotonic() + timeout
    while True:
        s = master.read_u16(NODE, STATUS)
        if pred(s):
            return s
        assert time.monotonic() < deadline, f"no status {what} within {timeout} s: last {status_text(s)}"


def test_immediate_stop_over_sdo_during_the_ramp_in_pre_operational(link, ax, master):
    """CiA 301's default error behaviour (0x1029:1 = 0): the lost master takes the node to
    pre-operational, so no RPDO reaches it; a master still talks SDO, and %Q16 written into
    0x2000 stops the ramp."""
    assert master.read_u8(NODE, 0x1029, 1) == 0
    ax.set_profile(RAMP)
    hb = watch_the_master(master, 0)
    try:
        run_at_speed(ax)
        emark = link.emcy_mark()
        hb.stop()
        assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_PREOPERATIONAL) == STATE_PREOPERATIONAL
        poll_status(master, lambda s: bool(s & DECEL), 2.0, "decelerating")
        # The position first, then the velocity: the ramp from here is at least as long as
        # the one from this (lower or equal) velocity.
        p_read = master.read_i32(NODE, MOTOR)
        v_read = master.read_i32(NODE, VELOCITY)
        master.write_u16(NODE, CMD, 0, Q["estop"])
        master.write_u16(NODE, CMD, 0, 0)
        status = poll_status(master, lambda s: not s & MOVING, 2.0, "at rest")
        final = master.read_i32(NODE, MOTOR)
        left = ramp_steps_from(RAMP, v_read)
        print(f"\nSDO Immediate Stop: read {p_read} steps at {v_read} steps/s ({left:.0f} steps of ramp left); "
              f"stood at {final} ({final - p_read} steps after)")
        assert left >= MEANINGFUL, f"the stop came too late in the ramp ({left:.0f} steps left) to test it"
        assert final - p_read <= left / FAR_BELOW, f"{final - p_read} steps after the read; the ramp had {left:.0f}"
        assert status & ~AT_HOME == WATCHDOG, f"after Immediate Stop: {status_text(status)} (want %I8 only)"
        assert_heartbeat_emcy(link, emark)
        time.sleep(RAMP.time_d_ms / 1000)
        assert master.read_i32(NODE, MOTOR) == final and master.read_i32(NODE, SIM_MECH) == final
    finally:
        hb.close()
