"""stepnode's CiA 402 homing methods 7..14 and 23..30 on vcan: a home switch active over a
part of the travel only, between the two limit switches, checked against the text of
CiA 402-2 (IEC 61800-7-201), not against the node's code.

The standard: "These methods use a home switch which is active over only a portion of the
travel [...]. Using methods 7 to 10 the initial direction of movement shall be to the right
[positive], and using methods 11 to 14 the initial direction of movement shall be to the
left [negative] except if the home switch is active at the start of the motion. In this
case the initial direction of motion shall be dependent on the edge being sought. The home
position shall be at the index pulse on either side of the rising or falling edges of the
home switch [...]. If the initial direction of movement leads away from the home switch, the
drive shall reverse on encountering the relevant limit switch." Methods 23..30 are the same
without the index pulse: the home position is the switch's edge. The figures place each
method's home position; the ones played here:

  7   the first index pulse below the switch's lower edge (crossing it moving negative)
  12  the first index pulse below the switch's upper edge (entering it moving negative)
  26  the switch's upper edge, crossed moving positive

The layout and the home/limit/index helpers are test_cia402_modes.py's; the expected home
position is computed on the layout from these words.
"""

import pytest

from cia402_master import CW_ENABLE_OPERATION, MODE_HM, MODE_PP, POSITION_ACTUAL, STATE_TIMEOUT, VELOCITY_ACTUAL
from test_cia402_modes import (
    COMPLETED, IN_PROGRESS, NODE, NOT_STARTED, SIM_INPUTS, SIM_POSITION, Layout, boot, homing_sequence,
    homing_status, pp_move, run_homing, set_homing,
)

# A home switch 2000 steps wide (an index pulse inside it, at 3700) between limit switches
# at -3000 and 9000; the index pulse once per 2000 steps at 1700 + 2000 k.
WINDOW = dict(lower_limit=-3000, upper_limit=9000, home_position=2500, home_width=2000, marker_offset=1700)


def expected_home(method: int, m: Layout) -> int:
    lower_out = m.first(m.home, m.home_position, -1, False)  # leaving the lower edge downward
    upper_in = m.first(m.home, m.home_position + m.home_width, -1, True)  # entering the upper edge downward
    upper_out = m.first(m.home, m.home_position + m.home_width - 1, +1, False)  # leaving it upward
    if method == 7:
        return m.first(m.index, lower_out, -1, True)
    if method == 12:
        return m.first(m.index, upper_in, -1, True)
    if method == 26:
        return upper_out
    raise ValueError(method)


CASES = [  # method, start (mechanical), the limit switch the first search must turn back at
    (7, 0, None),  # below the switch, positive start: toward it
    (7, 6000, "positive"),  # above it: positive leads away, reverse at the positive limit
    (12, 0, "negative"),  # below it, negative start: away, reverse at the negative limit
    (26, 0, None),
]


@pytest.mark.parametrize("method,start,reverses", CASES)
def test_home_switch_between_the_limit_switches(master, start_node, tmp_path, method, start, reverses):
    node = boot(master, start_node, tmp_path)
    drive = node[1]
    layout = Layout(**WINDOW)
    layout.apply(master)
    offset = 123
    set_homing(drive, method, offset)
    if start:
        drive.profile(velocity=8000, acceleration=80000, deceleration=80000)
        drive.enable(MODE_PP)
        pp_move(drive, start)
        mark = drive.mark()
        drive.controlword(CW_ENABLE_OPERATION, MODE_HM)
        drive.wait_status(lambda f: f.mode == MODE_HM, STATE_TIMEOUT, mark, "with modes of operation display 6")
    else:
        drive.enable(MODE_HM)
    assert master.read_i32(NODE, SIM_POSITION) == start
    expect = expected_home(method, layout)
    node.pump(0.1)
    assert homing_status(drive.sw) == NOT_STARTED
    mmark = drive.motion_mark()

    frames, end = run_homing(node, timeout=25.0)
    seq = homing_sequence(frames)
    mechanical = master.read_i32(NODE, SIM_POSITION)
    path = [m.position for m in drive.motion_log[mmark:]]
    print(f"method {method} from {start}: home {expect}, homed at {mechanical}; TPDO1 {seq}; "
          f"travel {min(path, default=start)}..{max(path, default=start)}")
    assert seq[0] == IN_PROGRESS, frames
    assert seq[-1] == COMPLETED and set(seq) <= {IN_PROGRESS, "010", COMPLETED}, frames
    assert mechanical == expect, f"method {method}: homed at {mechanical}, the standard's home position is {expect}"
    assert master.read_u8(NODE, SIM_INPUTS) & 0x17 == layout.inputs(expect), "layout model and machine disagree"
    assert drive.read_i32(POSITION_ACTUAL) == offset
    assert drive.read_i32(VELOCITY_ACTUAL) == 0
    # The first search's direction, and its reversal at the limit switch when it led away.
    assert path, "no TPDO with the position during the homing"
    if reverses == "positive":
        assert max(path) >= layout.upper_limit - 100, f"did not go to the positive limit switch: {max(path)}"
    elif reverses == "negative":
        assert min(path) <= layout.lower_limit + 100, f"did not go to the negative limit switch: {min(path)}"
    else:
        assert layout.lower_limit < min(path) and max(path) < layout.upper_limit, (min(path), max(path))
