"""Axes 1 and 2 of one node moving at once, each over its own PDOs. Axis 2's PDOs (RPDO5-8,
TPDO5-7) are mapped but disabled by default (README: so they never collide with another
node's pre-defined IDs); the test enables them over SDO with free COB-IDs, as an integrator
would, and then drives axis 2 over PDOs only."""

from axis_helpers import (
    ACCEL, AT_HOME, DECEL, ERRORS, FAST, ILLEGAL, MOVING, NODE, SIM_MECH, SLOW, VALID, WATCHDOG, assert_duration,
    bit_intervals, boot, clear_and_profile, seq_text, sequence, set_position,
)

# COB-IDs nobody else uses on this bus: the pre-defined set of node 8, which is not there.
AX2_RPDO = [0x208, 0x308, 0x408, 0x508]
AX2_TPDO = [0x188, 0x288, 0x388]


def test_axis_two_axes_move_at_once(master, start_node):
    link = boot(master, start_node)
    ax1 = link.axes[1]
    clear_and_profile(ax1, FAST)

    # Axis 2's PDOs exist but are not valid (bit 31 of the COB-ID).
    for k in range(4):
        assert master.read_u32(NODE, 0x1404 + k, 1) & 0x80000000
    for k in range(3):
        assert master.read_u32(NODE, 0x1804 + k, 1) & 0x80000000
    ax2 = link.add_axis(2, AX2_RPDO, AX2_TPDO)
    for k, cob in enumerate(AX2_RPDO):
        master.write_u32(NODE, 0x1404 + k, 1, 0x80000000 | cob)  # the new ID, still invalid
        master.write_u32(NODE, 0x1404 + k, 1, cob)               # then valid
    for k, cob in enumerate(AX2_TPDO):
        master.write_u32(NODE, 0x1804 + k, 1, 0xC0000000 | cob)  # no RTR (bit 30) kept
        master.write_u32(NODE, 0x1804 + k, 1, 0x40000000 | cob)
    # A TPDO that appears sends its values once: axis 2 is still in its power-up state.
    link.pump(3.0, lambda: bool(ax2.status_log))
    assert ax2.status_log and ax2.status_log[0].status == WATCHDOG, ax2.status_log
    assert ax1.status == 0x0000  # axis 1 is not affected by any of this

    # Axis 2 answers on its own PDOs, with its own EMCY code (0xFF02, axis byte 2).
    clear_and_profile(ax2, SLOW)
    emark, mark1 = link.emcy_mark(), ax1.mark()
    ax2.command("abs", 100)  # no valid position yet: Illegal Move on axis 2 only
    assert ax2.wait_status(lambda s: bool(s & ERRORS), 3.0).status == ILLEGAL
    em = link.wait_emcy(0xFF02, emark)
    assert em.manufacturer[0] == ILLEGAL and em.manufacturer[3] == 2, em.manufacturer.hex()
    assert 0xFF01 not in link.emcy_codes(emark) and not ax1.since(mark1)
    mark = ax2.mark()
    ax2.command("clear")
    ax2.wait_status(lambda s: not s & ERRORS, 3.0, mark)

    set_position(ax1, 0)
    set_position(ax2, 0)
    m1, m2 = ax1.mark(), ax2.mark()
    ax2.command("rel", -2000)  # SLOW: 100..1000 steps/s, 500 ms ramp
    ax1.command("rel", 6000)   # FAST: 200..4000 steps/s, 100 ms ramp
    f1 = ax1.wait_stopped(m1, 20.0)
    f2 = ax2.wait_stopped(m2, 20.0)
    link.pump(0.2)
    assert f1[-1].position == 6000 and f2[-1].position == -2000
    assert master.read_i32(NODE, SIM_MECH, 0) == 6000
    assert master.read_i32(NODE, SIM_MECH + 0x100, 0) == -2000
    assert (f1[-1].status, f2[-1].status) == (VALID, VALID)
    # Both at the same time, each with its own profile.
    (mv1,) = bit_intervals(f1, MOVING)
    (mv2,) = bit_intervals(f2, MOVING)
    overlap = min(mv1[1], mv2[1]) - max(mv1[0], mv2[0])
    assert overlap > 1.0, f"the moves overlapped {overlap:.2f} s only"
    assert_duration("axis 1 acceleration", bit_intervals(f1, ACCEL)[0], FAST.time_a_ms)
    assert_duration("axis 2 acceleration", bit_intervals(f2, ACCEL)[0], SLOW.time_a_ms)
    assert_duration("axis 2 deceleration", bit_intervals(f2, DECEL)[0], SLOW.time_d_ms)
    assert sequence(f1, ~AT_HOME) == [0xA100, 0x8100, 0xC100, 0x0100], seq_text(sequence(f1))
    assert sequence(f2) == [0xA100, 0x8100, 0xC100, 0x0100], seq_text(sequence(f2))
    assert any(v.velocity == round(FAST.vel_r) for v in ax1.velocity_log)
    assert any(v.velocity == -round(SLOW.vel_r) for v in ax2.velocity_log)
    assert (ax2.position_log[-1].motor, ax2.position_log[-1].encoder) == (-2000, -2000)
    assert (ax1.position_log[-1].motor, ax1.position_log[-1].encoder) == (6000, 6000)
