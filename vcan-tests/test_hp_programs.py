"""The HP 44714A manual's example programs, run unchanged from examples/hp44714a/ with
`stepctl hp --program FILE` against a stepnode on a real bus (issue 11 item 19): Figure 3-3
"Sending Pulses To a Motor" (its second block replacing lines 70-90, PAUSE going on when
the motor has stopped), the interrupt example of 3-16 (three BEEPs: after the MOVE, at
1000 Hz, at HALT SGL) and the WIDTH interrupt example of 3-28 (two: at 2 ms, at HALT SGL)."""

import subprocess
import time

import pytest

from conftest import CHANNEL, REPO_ROOT

NODE = 5
EXAMPLES = REPO_ROOT / "examples" / "hp44714a"


@pytest.fixture
def stepctl(stepctl_bin, tmp_path):
    p = stepctl_bin

    def run(*args, timeout=60):
        return subprocess.run([str(p), "--iface", CHANNEL, *map(str, args)], capture_output=True, text=True,
                              timeout=timeout, cwd=str(tmp_path), stdin=subprocess.DEVNULL)
    return run


@pytest.fixture
def node(master, start_node):
    start_node(NODE)
    master.nmt_start(0)
    time.sleep(0.2)
    return master


def program(stepctl, master, name, timeout):
    r = stepctl("hp", "--program", EXAMPLES / name, "--node", NODE, timeout=timeout)
    master.flush()  # stepctl's SDO answers are on the bus too
    print(r.stdout, r.stderr)
    assert r.returncode == 0, f"{name}: {r.stderr}"
    return r


def test_figure_3_3_sending_pulses_to_a_motor(node, stepctl):
    r = program(stepctl, node, "figure-3-3.bas", timeout=300)
    # The listing's second block replaced lines 70, 80 and 90 of the first.
    assert r.stderr.count("replaces the earlier line") == 3, r.stderr
    # MOVE 20 (200 pulses at PSCALE 0.1) and MOVE -30 (300), each after DELAY 5 and a TRIG;
    # then SUSTAIN 10, 50, 0 forward and -10 back, HALT SGL. PULSE SS: forward on PSTP,
    # backward on NDIR.
    pstp = node.read_u32(NODE, 0x2016, 8)
    ndir = node.read_u32(NODE, 0x2016, 9)
    assert pstp > 200 + 1000, pstp  # the MOVE and at least 10 s of SUSTAIN 10 (100 Hz)
    assert ndir > 300 + 500, ndir
    assert node.read_u8(NODE, 0x2018, 0) == 1  # DONE? 1: ended by HALT SGL
    assert node.read_u8(NODE, 0x2019, 0) == 0  # no error number
    assert node.read_i32(NODE, 0x5003, 0) == pstp - ndir  # the simulated motor followed


def test_interrupt_example_beeps_three_times(node, stepctl):
    r = program(stepctl, node, "interrupt-example.bas", timeout=120)
    assert r.stdout.count("BEEP") == 3, r.stdout
    intr = [line for line in r.stdout.splitlines() if line.startswith("INTR")]
    assert intr == ["INTR channel 0: pulses stopped following a MOVE",
                    "INTR channel 0: the SUSTAIN frequency or width was reached",
                    "INTR channel 0: HALT SGL stopped pulses"], intr
    assert node.read_u8(NODE, 0x201D, 1) == 1  # the routine re-enabled it


def test_width_interrupt_example_beeps_twice(node, stepctl):
    r = program(stepctl, node, "width-interrupt-example.bas", timeout=120)
    assert r.stdout.count("BEEP") == 2, r.stdout
    assert "the SUSTAIN frequency or width was reached" in r.stdout
    # PROFILE WIDTH ... 20E-3: 50 pulses a second for about 10 s.
    pulses = node.read_u32(NODE, 0x2016, 8)
    assert 450 <= pulses <= 600, pulses
