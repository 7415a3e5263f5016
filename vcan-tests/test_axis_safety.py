"""The axis' protective behaviour over PDOs (SPM30 3.1, 3.3.1, chapters 4-5; STP100 6.3.3):
end limits, the emergency stop input, a stalled motor seen by the encoder, and the loss of
the master (heartbeat consumer 0x1016). Errors latch in %I1..%I8, raise EMCY 0xFF01
(manufacturer bytes: the new error bits, the status word, the axis) and block every
command but Clear Errors."""

import time

import pytest

from axis_helpers import (
    DECEL, E_STOP, EMCY_AXIS1, EMCY_HEARTBEAT, ERRORS, LOWER, MOVING, NODE, SIM_ESTOP, SIM_FAULTS, SIM_SWITCHES,
    SLOW, STALLED, UPPER, VALID, WATCHDOG, HeartbeatSender, assert_duration, bit_intervals, link, ax, seq_text,
    sequence, set_position, status_text,
)

_ = (link, ax)  # fixtures


def assert_axis_emcy(link, mark, bits, axis=1):
    em = link.wait_emcy(0xFF00 + axis, mark)
    assert em.error_register & 0x81 == 0x81, f"error register 0x{em.error_register:02X}"
    assert em.manufacturer[0] == bits and em.manufacturer[3] == axis, em.manufacturer.hex()
    status = em.manufacturer[1] | em.manufacturer[2] << 8
    assert status & bits, status_text(status)
    return em


def assert_still(ax, duration=0.4):
    before = ax.mechanical()
    seen = ax.quiet(duration)
    assert not [s for s in seen if s.status & MOVING], f"moved: {seen}"
    assert ax.mechanical() == before


def clear(ax):
    mark = ax.mark()
    ax.command("clear")
    return ax.wait_status(lambda s: not s & ERRORS, 3.0, mark, "after Clear Errors")


@pytest.mark.parametrize("side", ["lower", "upper"])
def test_axis_end_limit(link, ax, master, side):
    sign, bit = (-1, LOWER) if side == "lower" else (1, UPPER)
    # A closer limit than the default +-100000 (0x5000 sub 3/4 lower, 5/6 upper).
    master.write_u8(NODE, SIM_SWITCHES, 3 if side == "lower" else 5, 1)
    master.write_i32(NODE, SIM_SWITCHES, 4 if side == "lower" else 6, sign * 1500)
    set_position(ax, 0)
    emark = link.emcy_mark()
    frames = ax.move("rel", sign * 100000)
    last = frames[-1]
    # 3.3.1: the end limit stops the motion at once and the position is no longer valid.
    assert last.status & ERRORS == bit and not last.status & VALID, last
    assert last.position == sign * 1500 and ax.mechanical() == sign * 1500
    assert not any(f.status & DECEL for f in frames), f"ramped down into the limit: {frames}"
    assert_axis_emcy(link, emark, bit)
    # 3.1: no other command while the error is latched (not even away from the limit).
    ax.command("rel", -sign * 500)
    assert_still(ax)
    emark = link.emcy_mark()
    assert clear(ax).status == 0x0000
    link.wait_emcy(0x0000, emark)
    # Toward the active limit: refused, the error latches again.
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("rel", sign * 10)
    assert ax.wait_status(lambda s: bool(s & ERRORS), 3.0, mark).status & ERRORS == bit
    assert_axis_emcy(link, emark, bit)
    assert_still(ax)
    clear(ax)
    # Away from it: a normal move.
    frames = ax.move("rel", -sign * 500)
    assert frames[-1].position == sign * 1000 and ax.mechanical() == sign * 1000
    assert not frames[-1].status & ERRORS


def test_axis_emergency_stop_input(link, ax, master):
    set_position(ax, 0)
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("rel", 20000)
    ax.wait_status(lambda s: s == MOVING | VALID, 5.0, mark, "running")
    link.pump(5.0, lambda: ax.position_log[-1].motor > 2000)
    master.write_u8(NODE, SIM_ESTOP, 0, 1)  # the e-stop input goes active
    frames = ax.wait_stopped(mark)
    last = frames[-1]
    assert last.status & ERRORS == E_STOP and not last.status & VALID, last
    assert not any(f.status & DECEL for f in frames), f"ramped down on e-stop: {seq_text(sequence(frames))}"
    assert_axis_emcy(link, emark, E_STOP)
    stopped = ax.mechanical()
    assert 2000 < stopped < 20000 and stopped == last.position
    assert_still(ax)
    # Clear with the input still active: cleared, but no move can start.
    assert clear(ax).status == 0x0000
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("rel", 100)
    assert ax.wait_status(lambda s: bool(s & ERRORS), 3.0, mark).status & ERRORS == E_STOP
    assert_axis_emcy(link, emark, E_STOP)
    assert ax.mechanical() == stopped
    # Input released, errors cleared: motion again.
    master.write_u8(NODE, SIM_ESTOP, 0, 0)
    clear(ax)
    assert ax.move("rel", 100)[-1].position == stopped + 100
    assert ax.mechanical() == stopped + 100


# (module model 0x2009:11, tolerance 0x2009:4, STP100 checkbox 0x2009:5, stall expected)
STALL_RULES = [(0, 10, 0, True), (0, 0, 1, False), (1, 0, 1, True), (1, 10, 0, False)]


@pytest.mark.parametrize("model,tolerance,checkbox,detection", STALL_RULES,
                         ids=["spm30-tolerance", "spm30-no-tolerance", "stp100-checkbox", "stp100-no-checkbox"])
def test_axis_stalled_motor(link, ax, master, model, tolerance, checkbox, detection):
    # SPM30 5.4: stall detection whenever the tolerance is non-zero; STP100 6.3.3: when its
    # "Enable Stall Detection" is checked. Quadrature encoder, 2000 steps/rev and 500 lines
    # decoded x4 (0x2009:12) = 2000 counts: multiplier 1, divisor 1.
    master.write_u8(NODE, 0x2009, 11, model)
    master.write_u8(NODE, 0x2009, 1, 1)
    master.write_u8(NODE, 0x2009, 12, 4)
    master.write_u8(NODE, 0x2009, 2, 1)
    master.write_u8(NODE, 0x2009, 3, 1)
    master.write_u8(NODE, 0x2009, 4, tolerance)
    master.write_u8(NODE, 0x2009, 5, checkbox)
    master.write_u8(NODE, SIM_FAULTS, 3, 1)            # the load jams above 800
    master.write_i32(NODE, SIM_FAULTS, 4, 800)
    set_position(ax, 0)
    assert ax.position_log[-1].encoder == 0
    emark = link.emcy_mark()
    frames = ax.move("rel", 5000)
    link.pump(0.2)
    last = frames[-1]
    assert ax.mechanical() == 800
    assert ax.position_log[-1].encoder == 800  # the encoder follows the load, not the steps
    if detection:
        # Encoder velocity below 10% of the commanded one: Motor Stalled, stop at once.
        assert last.status & ERRORS == STALLED and not last.status & VALID, last
        assert 800 <= last.position <= 900, f"stopped {last.position - 800} steps after the jam"
        assert not any(f.status & DECEL for f in frames), frames
        assert_axis_emcy(link, emark, STALLED)
        ax.command("rel", 100)
        assert_still(ax)
    else:
        assert last.status & ERRORS == 0 and last.position == 5000, last
        assert EMCY_AXIS1 not in link.emcy_codes(emark)


def test_axis_heartbeat_loss_decelerates_and_latches_watchdog(link, ax, master):
    ax.set_profile(SLOW)  # running 1000 steps/s, deceleration (AQ7) 300 ms
    hb = HeartbeatSender(0x7F, 0.1).start()
    try:
        # 0x1016:1 = node 0x7F, 300 ms: the node watches the test's heartbeat. 0x1029:1 = 1:
        # the error leaves the node operational, so its TPDOs show the ramp down.
        master.write_u32(NODE, 0x1016, 1, (0x7F << 16) | 300)
        master.write_u8(NODE, 0x1029, 1, 1)
        time.sleep(0.5)
        set_position(ax, 0)
        mark, emark = ax.mark(), link.emcy_mark()
        ax.command("rel", 200000)
        ax.wait_status(lambda s: s == MOVING | VALID, 5.0, mark, "running")
        ax.quiet(0.5)
        assert ax.status == MOVING | VALID, "stopped while the heartbeat was there"
        assert not link.emcy_codes(emark)
        hb.stop()
        last_beat = hb.last_sent
        frames = ax.wait_stopped(mark, 10.0)
        # Ramp down (not a sudden stop) and latch %I8.
        seq = sequence(frames)
        assert seq[-2:] == [MOVING | DECEL | VALID | WATCHDOG, VALID | WATCHDOG], seq_text(seq)
        (dec,) = bit_intervals(frames, DECEL)
        assert_duration("deceleration after the master was lost", dec, SLOW.time_d_ms)
        delay = dec[0] - last_beat
        assert 0.28 <= delay <= 0.6, f"ramp down {delay * 1000:.0f} ms after the last heartbeat (timeout 300 ms)"
        assert EMCY_HEARTBEAT in link.emcy_codes(emark)
        assert_axis_emcy(link, emark, WATCHDOG)
        assert frames[-1].position == ax.mechanical()
        # Nothing moves until the master is back and clears the error.
        ax.command("rel", 100)
        assert_still(ax)
        hb = HeartbeatSender(0x7F, 0.1).start()
        time.sleep(0.4)
        assert ax.status & WATCHDOG
        # (The node latches %I8 on its other, idle axes too, so their EMCYs 0xFF02/0xFF03
        # stay active and no error-reset EMCY follows this Clear Errors of axis 1.)
        assert clear(ax).status == VALID
        stopped = frames[-1].position
        assert ax.move("rel", 300)[-1].position == stopped + 300
    finally:
        hb.close()


def test_axis_heartbeat_loss_with_the_standard_error_behaviour(link, ax, master):
    """0x1029:1 = 0 (CiA 301's default): a heartbeat consumer timeout takes an operational
    node to pre-operational, announced by a heartbeat 0x7F at once, and the axis still ramps
    down and latches %I8 (read over SDO: pre-operational sends no TPDOs)."""
    assert master.read_u8(NODE, 0x1029, 1) == 0
    ax.set_profile(SLOW)
    hb = HeartbeatSender(0x7F, 0.1).start()
    try:
        master.write_u32(NODE, 0x1016, 1, (0x7F << 16) | 300)
        time.sleep(0.5)
        set_position(ax, 0)
        mark = ax.mark()
        ax.command("rel", 200000)
        ax.wait_status(lambda s: s == MOVING | VALID, 5.0, mark, "running")
        hb.stop()
        assert master.wait_heartbeat(NODE, timeout=2.0, state=0x7F) == 0x7F, "not pre-operational"
        deadline = time.monotonic() + 5.0
        status = master.read_u16(NODE, 0x2001)
        while status & MOVING and time.monotonic() < deadline:
            time.sleep(0.05)
            status = master.read_u16(NODE, 0x2001)
        assert not status & MOVING and status & WATCHDOG, status_text(status)
    finally:
        hb.close()
