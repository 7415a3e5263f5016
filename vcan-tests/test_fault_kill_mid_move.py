"""The node killed with -9 in the middle of a move and started again (issue 14): it boots
in the power-up state the manuals give (SPM30 3.1: every status bit off but %I8, position
0 (3.3.1), no motion until Clear Errors; the HP channel done and without error), and the
parameters stored before the move are intact while a value written after the save is not
kept. Trials: $STEPNODE_MOVE_KILL_TRIALS (default 3), each killed at a random point of an
accelerating or running move."""

from __future__ import annotations

import os
import random
import signal
import time

NODE = 34
SAVE = 0x65766173
TRIALS = int(os.environ.get("STEPNODE_MOVE_KILL_TRIALS", "3"))

CMD, STATUS, DEST, PROFILE = 0x2000, 0x2001, 0x2002, 0x2003
MOTOR, ENCODER, VELOCITY, PHASE, DONE, HP_ERROR = 0x2005, 0x2006, 0x2007, 0x2008, 0x2018, 0x2019
SIM_MECH = 0x5003
REL, CLEAR = 1 << 7, 1 << 13  # %Q8 Move Relative, %Q14 Clear Errors
WATCHDOG, MOVING = 0x0080, 0x8000
# %AQ3..%AQ7: 10 pulses/s per unit, base 200 /s, running 4000 /s, 100 ms ramps; not the defaults
STORED_PROFILE = [60, 20, 400, 100, 100]


def command(master, bits: int) -> None:
    """A command acts on its OFF->ON edge: the bit, then the word without it."""
    master.write_u16(NODE, CMD, 0, bits)
    master.write_u16(NODE, CMD, 0, 0)


def wait_until(pred, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while not (value := pred()):
        assert time.monotonic() < deadline, f"not {what} within {timeout} s"
        time.sleep(0.05)
    return value


def test_killed_mid_move_the_node_boots_in_its_power_up_state_with_stored_parameters_intact(
        master, start_node, tmp_path):
    state = tmp_path / "state"
    rng = random.Random(int(os.environ.get("STEPNODE_MOVE_KILL_SEED", "14")))
    node = start_node(NODE, state_dir=state)
    for sub, v in enumerate(STORED_PROFILE, start=1):
        master.write_u16(NODE, PROFILE, sub, v)
    master.write_u16(NODE, 0x1017, 0, 250)
    master.write_u32(NODE, 0x2F00, 1, 0xCAFE0034)
    master.write_u32(NODE, 0x1010, 1, SAVE)

    for trial in range(1, TRIALS + 1):
        master.write_u32(NODE, 0x2F00, 2, 0xBAD00000 + trial)  # after the save: lost with the process
        for word in (0, CLEAR, 0):
            master.write_u16(NODE, CMD, 0, word)
        assert master.read_u16(NODE, STATUS) & 0xFF == 0, "errors still latched after Clear Errors"
        master.write_i32(NODE, DEST, 0, 40_000)  # 10 s at 4000 steps/s
        command(master, REL)
        time.sleep(rng.uniform(0.05, 1.5))
        status, motor = master.read_u16(NODE, STATUS), master.read_i32(NODE, MOTOR)
        assert status & MOVING and 0 < motor < 40_000, f"trial {trial}: not moving (0x{status:04X}, {motor})"
        assert node.kill() == -signal.SIGKILL

        master.flush()
        node = start_node(NODE, state_dir=state)
        # SPM30 3.1 / 3.3.1: after power-up only %I8; position 0; at rest; HP DONE? 0, no error.
        after = {"status": master.read_u16(NODE, STATUS), "motor": master.read_i32(NODE, MOTOR),
                 "encoder": master.read_i32(NODE, ENCODER), "velocity": master.read_i32(NODE, VELOCITY),
                 "phase": master.read_u8(NODE, PHASE), "done": master.read_u8(NODE, DONE),
                 "hp_error": master.read_u8(NODE, HP_ERROR)}
        expected = {"status": WATCHDOG, "motor": 0, "encoder": 0, "velocity": 0, "phase": 0, "done": 0,
                    "hp_error": 0}
        assert after == expected, f"trial {trial} (killed at {motor} steps): power-up state {after}"
        assert [master.read_u16(NODE, PROFILE, s) for s in range(1, 6)] == STORED_PROFILE
        assert master.read_u16(NODE, 0x1017) == 250
        assert master.read_u32(NODE, 0x2F00, 1) == 0xCAFE0034
        assert master.read_u32(NODE, 0x2F00, 2) == 0  # never saved

        # %I8 latched: a move before Clear Errors is not obeyed (SPM30 3.1/3.2).
        master.write_i32(NODE, DEST, 0, 500)
        command(master, REL)
        time.sleep(0.4)
        assert (master.read_i32(NODE, MOTOR), master.read_i32(NODE, SIM_MECH)) == (0, 0), "moved before Clear Errors"

    # After the last restart the axis works as before: Clear Errors, then a move completes.
    command(master, CLEAR)
    master.write_i32(NODE, DEST, 0, 500)
    command(master, REL)
    wait_until(lambda: master.read_i32(NODE, MOTOR) == 500 and not master.read_u16(NODE, STATUS) & MOVING, 5.0,
               "at 500 after Clear Errors and a move")
    assert master.read_i32(NODE, SIM_MECH) == 500
