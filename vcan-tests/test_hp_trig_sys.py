"""HP 44714A TRIG SYS on a real bus: three axes on two stepnode processes (node 5 with two
axes, node 6 with one) are armed with `stepctl hp "TRIG SYS; MOVE 40 NOWAIT"` and started by
one SYNC frame. Each node records the time of the first step it generated (0x2n1E:2, node
clock CLOCK_MONOTONIC in us, the same clock in both processes) and the time of the SYNC that
triggered it (0x2n1E:1); the first steps fall within one engine tick (the node's --tick-us)
of each other, and each one's offset from its trigger is the profile's (same on every axis).
The simulated machines (0x5n03) show the steps were taken, and none before the SYNC."""

import subprocess
import time

import pytest

from conftest import CHANNEL

A, B = 5, 6
TICK_US = 1000
AXES = [(A, 0), (A, 1), (B, 0)]  # (node, HP channel)


@pytest.fixture
def stepctl(stepctl_bin, tmp_path):
    p = stepctl_bin

    def run(*args, timeout=30):
        r = subprocess.run([str(p), "--iface", CHANNEL, *map(str, args)], capture_output=True, text=True,
                           timeout=timeout, cwd=str(tmp_path), stdin=subprocess.DEVNULL)
        return r
    return run


def hp(stepctl, master, node, channel, words):
    r = stepctl("hp", words, "--node", node, "--axis", channel)
    master.flush()  # stepctl's SDO answers are on the bus too: not for our master
    assert r.returncode == 0, f"stepctl hp {words!r} node {node} ch {channel}: {r.stderr}"
    return r.stdout


def test_three_axes_on_two_nodes_start_on_one_sync(master, start_node, stepctl, tmp_path):
    cfg = tmp_path / "two-axes.toml"
    cfg.write_text("axes = 2\n")
    start_node(A, ["--config", cfg, "--tick-us", TICK_US])
    start_node(B, ["--tick-us", TICK_US])
    master.nmt_start(0)
    time.sleep(0.2)

    for node, ch in AXES:
        # A profile with a real ramp: 200 Hz start, so the first step is 5 ms after the trigger.
        hp(stepctl, master, node, ch, "PROFILE FREQ 200 2000 4000 50E-6; TRIG SYS; MOVE 40 NOWAIT")
        out = hp(stepctl, master, node, ch, "DONE?")
        assert out.startswith("DONE? -3"), out  # waiting for trigger
    time.sleep(0.3)
    for node, ch in AXES:
        assert master.read_i32(node, 0x5003 + 0x100 * ch) == 0, "a step before the SYNC"

    master.sync()
    time.sleep(1.0)

    firsts, triggers, offsets = [], [], []
    for node, ch in AXES:
        base = 0x2000 + 0x100 * ch
        assert master.read_i32(node, 0x5003 + 0x100 * ch) == 40
        assert hp(stepctl, master, node, ch, "DONE?").startswith("DONE? 0"), (node, ch)
        triggers.append(master.read_u32(node, base + 0x1E, 1))
        firsts.append(master.read_u32(node, base + 0x1E, 2))
        offsets.append(master.read_i32(node, base + 0x1E, 3))
    spread = max(firsts) - min(firsts)
    print(f"first steps (us, node clock): {firsts}, triggers: {triggers}, offsets: {offsets}, spread {spread} us")
    # Same profile everywhere: the first step is the same time after each node's trigger
    # (just under 1/200 Hz = 5 ms, to the rounding of one microsecond).
    assert max(offsets) - min(offsets) <= 1, offsets
    assert 4000 <= offsets[0] <= 5000, offsets
    # Both axes of one node share the trigger exactly; the nodes differ by when each process
    # read the SYNC frame. All first steps lie within one engine tick.
    assert triggers[0] == triggers[1]
    assert spread <= TICK_US, f"first steps {firsts} spread {spread} us > one tick ({TICK_US} us)"


def test_trig_hold_cancels_and_a_sync_then_starts_nothing(master, start_node, stepctl):
    start_node(A)
    master.nmt_start(A)
    hp(stepctl, master, A, 0, "TRIG SYS; MOVE 10 NOWAIT; TRIG HOLD")
    assert hp(stepctl, master, A, 0, "DONE?").startswith("DONE? 0")
    master.sync()
    time.sleep(0.5)
    assert master.read_i32(A, 0x5003) == 0
    # TRIG SGL now has nothing to fire: error 90, explained in the manual's words.
    r = stepctl("hp", "TRIG SGL", "--node", A, "--axis", 0)
    assert r.returncode == 1
    assert 'ERROR 90 "NO ACTION DEFINED"' in r.stderr
