"""FIND HOME UP / DOWN (%Q4 / %Q5) over PDOs (SPM30 chapter 4, STP113 C1.2.1, STP100 5.3.2
and 3.2.3): the normal method (stop on the origin, back off at base velocity, clear it for
50 ms, re-approach at base velocity) and the simple method (stop on the origin), with the
home switch or the encoder marker as the origin, with and without limit-switch
qualification. The home cam of the simulated machine covers 1000..1049 (0x5000:1/2), so the
origin is 1000 approached from below and 1049 approached from above."""

import pytest

from axis_helpers import (
    AT_HOME, DECEL, ERRORS, FAST, NODE, PH_BASE, SIM_ENCODER, SIM_SWITCHES, VALID, link, ax,
    seq_text, sequence, set_position,
)

_ = (link, ax)  # fixtures

DEST = 4321  # loaded into MOTOR (and ENCODER) POSITION when home is found
LOWER_AT, UPPER_AT = -4000, 4600


def check_found(ax, frames, mechanical):
    link = ax.link
    link.pump(0.2)
    last = frames[-1]
    assert last.status == VALID | AT_HOME, f"final status {last}"
    assert last.position == DEST
    assert (ax.position_log[-1].motor, ax.position_log[-1].encoder) == (DEST, DEST)
    assert ax.mechanical() == mechanical
    # Step 1: CURRENT POSITION VALID goes off at once, and stays off until home is found.
    assert all(not f.status & VALID for f in frames[:-1]), frames
    # The axis stops on the origin: never by a deceleration ramp at the end.
    assert not frames[-2].status & DECEL


@pytest.mark.parametrize("method", ["normal", "simple"])
@pytest.mark.parametrize("direction", ["up", "down"])
def test_axis_find_home_switch(link, ax, master, direction, method):
    if method == "simple":
        master.write_u8(NODE, 0x2009, 6, 1)  # STP113 C1.2.1 byte 2 = 1 / STP100 "Simple Method"
    set_position(ax, 777)
    if direction == "down":
        assert ax.move("rel", 2000)[-1].position == 2777  # start above the cam (mechanical 2000)
    sign = 1 if direction == "up" else -1
    vmark, mark = len(ax.velocity_log), ax.mark()
    ax.command(f"home_{direction}", DEST)
    frames = ax.wait_stopped(mark, 20.0)
    check_found(ax, frames, 1000 if direction == "up" else 1049)
    seq = sequence(frames)
    vel = ax.velocity_log[vmark:]
    if method == "simple":
        # Seek at running velocity, stop on the origin: done.
        assert seq == [0xA000, 0x8000, 0x1100], seq_text(seq)
        assert all(v.velocity * sign >= 0 for v in vel), vel
        assert PH_BASE not in [v.phase for v in vel]
    else:
        # Stop on the origin, back off at base velocity (still on it), leave it, come back.
        assert seq == [0xA000, 0x8000, 0x9000, 0x8000, 0x1100], seq_text(seq)
        base = [v for v in vel if v.phase == PH_BASE]
        assert base and base[0].velocity == -sign * round(FAST.vel_b), vel  # step 4/5: the other way
        # Steps 5-6: off the origin for 50 ms at base velocity before the final approach.
        off = next(i for i, f in enumerate(frames) if f.status == 0x8000 and i > 1)
        assert frames[-1].t - frames[off].t >= 0.045, frames
        # The back-off and re-approach are at base velocity, so they stay close to the cam
        # (positions before the final one count from the Set Current Position of 777).
        origin = (1000 if direction == "up" else 1049) + 777
        near = [p.motor for p in ax.position_log if frames[off].t <= p.t < frames[-1].t]
        assert near and all(abs(p - origin) <= 20 for p in near), near


# (module model 0x2009:11, origin source marker 0x2009:7, limit qualified 0x2009:8)
MARKER_HOMING = {"stp100-marker": (1, 1, 0), "stp100-marker-limit-qualified": (1, 1, 1),
                 "spm30-quad": (0, 0, 0)}


@pytest.mark.parametrize("setup", list(MARKER_HOMING))
@pytest.mark.parametrize("direction", ["up", "down"])
def test_axis_find_home_on_the_encoder_marker(link, ax, master, direction, setup):
    # Wiring: a quadrature encoder, 2000 steps = 500 lines decoded x4, markers 4 steps wide
    # at 300 + k*2000; limits at -4000 and 4600 (closer than the default +-100000). The
    # STP100 takes the marker and the limit qualification as options (3.2.3); the SPM30 does
    # both with QUAD and nothing else (4 FIND HOME step 3).
    model, marker, qualified = MARKER_HOMING[setup]
    qualified = qualified or model == 0
    master.write_u8(NODE, 0x2009, 11, model)
    master.write_u8(NODE, 0x2009, 1, 1)              # encoder quadrature
    master.write_u8(NODE, 0x2009, 12, 4)
    master.write_u8(NODE, 0x2009, 7, marker)         # origin source: the marker (STP100 3.2.3)
    master.write_u8(NODE, 0x2009, 8, int(qualified and model == 1))  # limit-switch qualified
    master.write_i32(NODE, SIM_ENCODER, 3, 300)
    master.write_i32(NODE, SIM_SWITCHES, 4, LOWER_AT)
    master.write_i32(NODE, SIM_SWITCHES, 6, UPPER_AT)
    set_position(ax, 0)
    sign = 1 if direction == "up" else -1
    pmark, mark, emark = len(ax.position_log), ax.mark(), link.emcy_mark()
    ax.command(f"home_{direction}", DEST)
    frames = ax.wait_stopped(mark, 30.0)
    if qualified:
        # Step 3 becomes: run to the end limit of the direction, stop there (no limit error),
        # then the marker closest to the limit: -3700..-3697 above -4000, 4300..4303 below
        # 4600; the last approach is toward the limit: -3697 from above, 4300 from below.
        expect = -3697 if direction == "down" else 4300
        limit = LOWER_AT if direction == "down" else UPPER_AT
        reach = [p.motor for p in ax.position_log[pmark:] if p.t < frames[-1].t]  # before DEST is loaded
        extreme = min(reach) if sign < 0 else max(reach)
        assert abs(extreme - limit) <= 10, f"turned at {extreme}, not at the limit {limit}"
    else:
        # The first marker in the direction of travel: 300..303 above 0, -1700..-1697 below.
        expect = 300 if direction == "up" else -1697
        reach = [p.motor for p in ax.position_log[pmark:] if p.t < frames[-1].t]  # before DEST is loaded
        assert all(abs(r) <= 1800 for r in reach), f"went beyond the first marker: {reach}"
    check_found(ax, frames, expect)
    assert not any(f.status & ERRORS for f in frames)
    assert 0xFF01 not in link.emcy_codes(emark)
