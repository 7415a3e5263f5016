"""Axis 1 of node 7 driven over its PDOs only (SPM30 chapters 3-4, appendix B/C; STP100
chapter 5): power-up and Clear Errors, relative and absolute moves with the ramp times of
STPCALC, Set Current Position, jog, Decelerate and Stop / Resume, indexed and repeated
moves. The simulated machine is set up over SDO 0x5000 (that is wiring it); every command
goes out in RPDO1-4 and everything checked comes back in TPDO1-3 and EMCY (plus the load's
mechanical position, 0x5003, read from the simulation)."""

import time

import pytest

from axis_helpers import (
    ACCEL, AT_HOME, DECEL, ERRORS, FAST, ILLEGAL, MOVING, NODE, PH_ACC, PH_DEC, PH_IDLE, PH_RUN, Q, RESUMABLE,
    SIM_SWITCHES, SLOW, VALID, WATCHDOG, Stpcalc, assert_duration, bit_intervals, boot, link,
    ax, seq_text, sequence, set_position,
)

_ = (link, ax)  # fixtures


def test_axis_power_up_status_then_clear_errors(master, start_node):
    lk = boot(master, start_node)
    a = lk.axes[1]
    # SPM30 3.1: after power-up every status bit is off except %I8; position 0 (3.3.1).
    first = a.status_log[0]
    assert (first.status, first.position) == (WATCHDOG, 0), f"first TPDO1 after NMT start: {first}"
    assert (a.position_log[0].motor, a.position_log[0].encoder) == (0, 0)
    assert (a.velocity_log[0].velocity, a.velocity_log[0].phase) == (0, PH_IDLE)

    # 3.1/3.2: while an error bit is on no command but Clear Errors is obeyed.
    a.set_profile(FAST)
    for name, dest in (("rel", 500), ("set", 77), ("home_up", 0), ("jog_up", 0)):
        a.command(name, dest)
    seen = a.quiet(0.8)
    assert not seen, f"commands acted before Clear Errors: {seen}"
    assert a.mechanical() == 0
    assert all(p.motor == 0 for p in a.position_log)

    mark = a.mark()
    a.command("clear")
    f = a.wait_status(lambda s: not s & ERRORS, 3.0, mark, "after Clear Errors")
    assert f.status == 0x0000 and f.position == 0

    # Now a command is obeyed.
    frames = a.move("rel", 500)
    assert frames[-1].position == 500 and a.mechanical() == 500
    assert frames[-1].status == 0x0000


def test_axis_move_relative_then_absolute_with_stpcalc_ramp_times(link, ax):
    ax.set_profile(SLOW)  # AQ3=600 AQ4=100 AQ5=1000 AQ6=500 AQ7=300

    # SPM30 3.3.1: MOVE ABSOLUTE needs CURRENT POSITION VALID: refused with Illegal Move.
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("abs", 500)
    f = ax.wait_status(lambda s: bool(s & ERRORS), 3.0, mark, "Illegal Move")
    assert f.status == ILLEGAL, f"status after MOVE ABSOLUTE without a valid position: {f}"
    em = link.wait_emcy(0xFF01, emark)
    assert em.error_register & 0x81 == 0x81, f"error register 0x{em.error_register:02X}"
    assert em.manufacturer == bytes([ILLEGAL, ILLEGAL, 0x00, 1, 0]), em.manufacturer.hex()
    assert not [s for s in ax.quiet(0.3) if s.status & MOVING]
    assert ax.mechanical() == 0

    mark = ax.mark()
    ax.command("clear")
    assert ax.wait_status(lambda s: not s & ERRORS, 3.0, mark).status == 0x0000
    link.wait_emcy(0x0000, emark)  # error reset

    # A relative move of 3000 from 0 (no valid position needed): a trapezoid.
    vmark, pmark = len(ax.velocity_log), len(ax.position_log)
    frames = ax.move("rel", 3000)
    link.pump(0.2)
    # accelerate -> run (passing the home cam at 1000..1049) -> decelerate -> stop
    assert sequence(frames) == [0xA000, 0x8000, 0x9000, 0x8000, 0xC000, 0x0000], seq_text(sequence(frames))
    assert frames[-1].position == 3000 and ax.mechanical() == 3000
    # STPCALC B1.3.11 / B1.3.13: Time_A = (AQ5-AQ4)*Z_A*5/24576 = 500.06 ms, Time_D (AQ7) = 300.07 ms.
    (acc,) = bit_intervals(frames, ACCEL)
    (dec,) = bit_intervals(frames, DECEL)
    assert_duration("acceleration", acc, SLOW.time_a_ms)
    assert_duration("deceleration", dec, SLOW.time_d_ms)
    (mov,) = bit_intervals(frames, MOVING)
    assert_duration("whole move (B1.3.15)", mov, SLOW.move_time_ms(3000), 60)
    # Position at the phase changes: acceleration pulses (B1.3.7) and deceleration pulses (B1.3.9).
    run_start = next(f for f in frames if f.status & MOVING and not f.status & (ACCEL | DECEL))
    dec_start = next(f for f in frames if f.status & DECEL)
    assert abs(run_start.position - SLOW.pulse_a) <= 15, (run_start, SLOW.pulse_a)
    assert abs(3000 - dec_start.position - SLOW.pulse_d) <= 15, (dec_start, SLOW.pulse_d)
    # TPDO3: base velocity at the start, running velocity AQ5*600/AQ3 = 1000 steps/s.
    vel = ax.velocity_log[vmark:]
    assert [v.phase for v in vel] == [PH_ACC, PH_RUN, PH_DEC, PH_IDLE], vel
    assert abs(vel[0].velocity - SLOW.vel_b) <= 10 and vel[1].velocity == round(SLOW.vel_r), vel
    assert vel[-1].velocity == 0
    # TPDO2 streams positions while moving, at most every 10 ms (inhibit time), ends at 3000.
    pos = ax.position_log[pmark:]
    gaps = [b.t - a.t for a, b in zip(pos, pos[1:])]
    assert len(pos) >= 60, f"only {len(pos)} TPDO2 during a {SLOW.move_time_ms(3000):.0f} ms move"
    # (Kernel receive times, so a late send may shorten one gap; without the inhibit time
    # TPDO2 would follow every 1 ms tick.)
    assert sorted(gaps)[len(gaps) // 10] >= 0.008, f"TPDO2 closer than the 10 ms inhibit time: {sorted(gaps)[:10]}"
    assert all(b.motor >= a.motor for a, b in zip(pos, pos[1:]))
    assert (pos[-1].motor, pos[-1].encoder) == (3000, 3000)  # no encoder: encoder = motor (5.1)

    # Set a position, then absolute moves.
    set_position(ax, 10000)
    vmark = len(ax.velocity_log)
    frames = ax.move("abs", 8000)  # 2000 down: ends at mechanical 1000, on the home cam
    assert frames[-1].position == 8000 and ax.mechanical() == 1000
    assert sequence(frames) == [0xA100, 0x8100, 0xC100, 0xD100, 0x1100], seq_text(sequence(frames))
    assert ax.velocity_log[vmark + 1].velocity == -round(SLOW.vel_r)  # down: negative
    # Absolute to where it is: nothing to do.
    ax.command("abs", 8000)
    assert not [s for s in ax.quiet(0.4) if s.status & MOVING]
    frames = ax.move("abs", 8250)
    assert frames[-1].position == 8250 and ax.mechanical() == 1250
    assert frames[-1].status == VALID


def test_axis_set_current_position(link, ax):
    set_position(ax, 12345)                      # SPM30 4 SET CURRENT POSITION
    assert ax.status == VALID
    assert ax.position_log[-1].encoder == 12345  # "(and into ENCODER POSITION)"
    assert ax.mechanical() == 0                  # no motion
    frames = ax.move("abs", 12845)
    assert frames[-1].position == 12845 and ax.mechanical() == 500
    set_position(ax, -8388608)                   # the minimum is legal (3.4)
    frames = ax.move("rel", 1000)
    assert frames[-1].position == -8387608 and ax.mechanical() == 1500
    # While moving only the stops are obeyed (3.2): a Set Current Position is ignored.
    mark = ax.mark()
    ax.command("rel", 2000)
    ax.wait_status(lambda s: s & MOVING and not s & ACCEL, 5.0, mark, "running")
    ax.command("set", 0)
    frames = ax.wait_stopped(mark)
    assert frames[-1].position == -8385608 and frames[-1].status & VALID
    assert ax.mechanical() == 3500


# SPM30 3.4 / B1.2: words outside the module's ranges are not legal; sent in an RPDO (which
# has no answer, unlike SDO's range abort) they make the next command an Illegal Move (%I4,
# EMCY 0xFF01) with no motion.
@pytest.mark.parametrize("word,value", [("destination", 8388608), ("destination", -8388609),
                                        ("AQ3", 10), ("AQ6", 0)])
def test_axis_illegal_words_over_rpdo_are_an_illegal_move(link, ax, word, value):
    set_position(ax, 0)
    assert ax.move("rel", 1000)[-1].position == 1000
    emark = link.emcy_mark()
    if word == "destination":
        ax.command("rel", value)
    else:
        ax.profile(value if word == "AQ3" else FAST.aq3, FAST.aq4, FAST.aq5, value if word == "AQ6" else FAST.aq6)
        ax.command("rel", 1000)
    seen = ax.quiet(1.5)
    assert ax.mechanical() == 1000, f"{word} = {value}: moved to {ax.mechanical()}: {seen}"
    assert any(s.status & ILLEGAL for s in seen), f"no Illegal Move: {seen}"
    assert 0xFF01 in link.emcy_codes(emark)


@pytest.mark.parametrize("direction", ["up", "down"])
def test_axis_jog_is_level_sensitive(link, ax, direction):
    sign = 1 if direction == "up" else -1
    vmark, mark = len(ax.velocity_log), ax.mark()
    ax.hold(f"jog_{direction}")
    ax.wait_status(lambda s: s & MOVING and not s & ACCEL, 5.0, mark, "running")
    ax.quiet(0.6)
    assert ax.status & MOVING, "jog stopped while the bit was held"
    held_at = ax.position_log[-1].motor
    assert sign * held_at > 1000
    ax.hold()  # release: decelerate and stop (SPM30 4 JOG)
    frames = ax.wait_stopped(mark)
    link.pump(0.2)
    assert sequence(frames, ~AT_HOME) == [0xA000, 0x8000, 0xC000, 0x0000], seq_text(sequence(frames))
    (acc,) = bit_intervals(frames, ACCEL)
    (dec,) = bit_intervals(frames, DECEL)
    assert_duration("jog acceleration", acc, FAST.time_a_ms)
    assert_duration("jog deceleration (AQ7 = 0: AQ6)", dec, FAST.time_d_ms)
    dec_start = next(f for f in frames if f.status & DECEL)
    ramp = sign * (frames[-1].position - dec_start.position)
    assert abs(ramp - FAST.pulse_d) <= 25, f"{ramp} steps of deceleration, STPCALC {FAST.pulse_d:.1f}"
    vel = ax.velocity_log[vmark:]
    assert [v.phase for v in vel] == [PH_ACC, PH_RUN, PH_DEC, PH_IDLE], vel
    assert vel[1].velocity == sign * round(FAST.vel_r)
    assert frames[-1].position == ax.mechanical() == ax.position_log[-1].motor
    assert not [s for s in ax.quiet(0.4) if s.status & MOVING]


def test_axis_decelerate_and_stop_then_resume_twice(link, ax):
    set_position(ax, 0)
    mark = ax.mark()
    ax.command("rel", 12000)
    for n, beyond in enumerate((2500, 6500)):
        link.pump(10.0, lambda: ax.position_log[-1].motor > beyond)
        stop_mark = ax.mark()
        ax.command("stop")  # %Q15
        frames = ax.wait_stopped(stop_mark - 1)
        # decelerate to base velocity, then stop; the move is resumable (%I10)
        assert sequence(frames[1:]) == [0xC100, 0x0300], seq_text(sequence(frames))
        (dec,) = bit_intervals(frames, DECEL)
        assert_duration(f"stop {n + 1}: deceleration", dec, FAST.time_d_ms)
        stopped = frames[-1].position
        assert beyond < stopped < 12000
        assert ax.mechanical() == stopped
        assert not [s for s in ax.quiet(0.3) if s.status & MOVING]
        resume_mark = ax.mark()
        ax.command("resume")  # %Q10: from where it left off
        f = ax.wait_status(lambda s: bool(s & MOVING), 3.0, resume_mark, "moving after Resume")
        assert f.status == 0xA100, f"resumed move starts accelerating, %I10 off: {f}"
    frames = ax.wait_stopped(resume_mark)
    assert frames[-1].position == 12000 and frames[-1].status == VALID  # the original target
    assert ax.mechanical() == 12000
    assert len(bit_intervals(ax.since(mark), MOVING)) == 3

    # 3.4 RESUME MOVE (3): any other command after the stop ends resumability.
    mark = ax.mark()
    ax.command("rel", 3000)
    link.pump(10.0, lambda: ax.position_log[-1].motor > 13000)
    ax.command("stop")
    frames = ax.wait_stopped(mark)
    assert frames[-1].status & RESUMABLE
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("set", 0)
    assert ax.wait_status(lambda s: not s & RESUMABLE, 3.0, mark).status == VALID
    ax.command("resume")
    assert ax.wait_status(lambda s: bool(s & ERRORS), 3.0, mark).status & ILLEGAL
    link.wait_emcy(0xFF01, emark)
    assert not [s for s in ax.since(mark) if s.status & MOVING]


# Index input at 2500..2509 (STP113 appendix C, STP100 5.3.5). FAST reaches its running
# velocity after ~211 steps, so a window opening at 1000 is legal.
INDEX_AT, INDEX_DEST = 2500, 700
INDEXED = Stpcalc(60, 20, 400, 100, 200)  # AQ7 = 200 ms
AQ10 = 50                                 # indexed deceleration


@pytest.mark.parametrize("window,final,decel_ms", [
    ((1000, 3500), INDEX_AT + INDEX_DEST, Stpcalc(60, 20, 400, 100, AQ10).time_d_ms),  # inside
    ((2600, 3500), 4000, INDEXED.time_d_ms),                                         # before the window
], ids=["index-inside-window", "index-outside-window"])
def test_axis_indexed_move(link, ax, master, window, final, decel_ms):
    master.write_i32(NODE, SIM_SWITCHES, 7, INDEX_AT)
    master.write_i32(NODE, SIM_SWITCHES, 8, 10)
    set_position(ax, 0)
    ax.set_profile(INDEXED, aq10=AQ10, aq8=INDEX_DEST)  # RPDO2 + RPDO3
    ax.window(*window)                                  # RPDO4
    frames = ax.move("indexed", 4000)                   # %Q11, DESTINATION 4000
    assert frames[-1].position == final and ax.mechanical() == final
    assert sequence(frames, ~AT_HOME) == [0xA100, 0x8100, 0xC100, 0x0100], seq_text(sequence(frames))
    (dec,) = bit_intervals(frames, DECEL)
    assert_duration("deceleration", dec, decel_ms)
    # Repeated without the index input wired: a plain relative move.
    master.write_i32(NODE, SIM_SWITCHES, 8, 0)
    assert ax.move("indexed", 4000)[-1].position == final + 4000


def test_axis_repeat_move_while_q12_is_held(link, ax):
    set_position(ax, 0)
    mark = ax.mark()
    ax.hold("repeat")
    ax.command("rel", 300)  # %Q8 pulse with %Q12 held (STP100 5.3.6)
    link.pump(10.0, lambda: len(bit_intervals(ax.since(mark), ACCEL)) >= 4)
    released = time.time()  # the clock of the frames' receive timestamps
    ax.hold()               # %Q12 off: the current move completes, no repeat
    frames = ax.wait_stopped(mark, 10.0)
    starts = [t_on for t_on, _ in bit_intervals(frames, ACCEL)]
    moves = len(starts)
    started_before = len([t for t in starts if t < released])
    assert started_before >= 4 and moves <= started_before + 1, (started_before, moves)
    assert frames[-1].position == 300 * moves and ax.mechanical() == 300 * moves
    # One uninterrupted run: MOVING never dropped between the repeats.
    assert sequence(frames, MOVING) == [MOVING, 0], seq_text(sequence(frames))
    assert not [s for s in ax.quiet(0.5) if s.status & MOVING]
    # Without %Q12 the same command moves once.
    assert ax.move("rel", 300)[-1].position == 300 * (moves + 1)


def test_axis_immediate_stop_and_command_priority(link, ax):
    set_position(ax, 0)
    mark, emark = ax.mark(), link.emcy_mark()
    ax.command("rel", 20000)
    link.pump(10.0, lambda: ax.position_log[-1].motor > 2000)
    ax.command("estop")  # %Q16 IMMEDIATE STOP: at once, and the position is no longer valid
    frames = ax.wait_stopped(mark)
    assert not any(f.status & DECEL for f in frames), seq_text(sequence(frames))
    assert frames[-1].status == 0x0000, frames[-1]  # not an error, not resumable, not valid
    stopped = frames[-1].position
    assert ax.mechanical() == stopped
    assert not [s for s in ax.quiet(0.3) if s.status & MOVING]
    assert 0xFF01 not in link.emcy_codes(emark)
    # SPM30 3.2: of several %Q going on at once the highest number is obeyed: %Q9 over %Q8.
    set_position(ax, 100)
    mark = ax.mark()
    ax.rpdo1(Q["rel"] | Q["abs"], 500)
    ax.rpdo1(0)
    frames = ax.wait_stopped(mark)
    assert frames[-1].position == 500 and ax.mechanical() == stopped + 400
