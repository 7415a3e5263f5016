"""The DDS bridge with real processes (issue 5), axis by axis: a stepnode on vcan0,
stepbridge, and cyclone_sub (Eclipse Cyclone DDS, built from the IDL alone, so every check
here is also proof that the topics are standard DDS). A move tracked, the late joiner,
LOST/dispose, restarts and two nodes are in test_bridge_dds.py.

What the bridge publishes is compared with what the node put on the bus: the TPDO1 status
words and TPDO2 positions the test's own master records (axis_helpers.NodeLink)."""

from __future__ import annotations

import time

from axis_helpers import (
    AT_HOME, FAST, MOVING, NODE, SIM_SWITCHES, VALID, boot, clear_and_profile, seq_text, sequence, set_position,
)
from bridge_helpers import DDS_TIMEOUT, cyclone, domain, start_bridge, status_changes, stepbridge_bin

_ = (cyclone, domain, start_bridge, stepbridge_bin)  # fixtures


def wait_discovered(cyc, node: int = NODE, axis: int = 1):
    """The bridge has read the node's mapping when its first AxisStatus arrives (it seeds
    every axis's status over SDO on discovery)."""
    cyc.wait(lambda: cyc.snapshot("AxisStatus", node, axis), DDS_TIMEOUT,
             f"the first AxisStatus of node {node} axis {axis}")


def wait_sdo_quiet(master, node: int = NODE, quiet_s: float = 0.5, timeout: float = 15.0):
    """Until no SDO request or answer of `node`'s default channel was seen for `quiet_s`."""
    deadline = time.monotonic() + timeout
    ids = (0x600 + node, 0x580 + node)
    while master.collect(quiet_s, lambda m: m.arbitration_id in ids):
        assert time.monotonic() < deadline, f"node {node}'s SDO channel never went quiet"


def test_every_status_transition_of_a_homing_and_a_move_arrives_in_order(master, start_node, start_bridge, cyclone):
    link = boot(master, start_node)
    ax = link.axes[1]
    # The home switch at +400 (width 50): Find Home Up runs into it and stops at home.
    master.write_i32(NODE, SIM_SWITCHES, 1, 400)
    master.write_i32(NODE, SIM_SWITCHES, 2, 50)
    start_bridge()  # after the node: discovered from its heartbeat, not its boot-up
    wait_discovered(cyclone)
    clear_and_profile(ax, FAST)
    link.pump(0.3)
    cyc_mark, bus_mark = cyclone.mark(), ax.mark()
    frames = ax.move("home_up")
    assert frames[-1].status & AT_HOME and frames[-1].status & VALID, seq_text(sequence(frames))
    frames = ax.move("abs", 1500)
    assert frames[-1].position == 1500 and not frames[-1].status & MOVING
    on_bus = sequence(ax.since(bus_mark))
    cyclone.wait(lambda: status_changes(cyclone.since(cyc_mark, "AxisStatus", NODE, 1))[-1:] == on_bus[-1:],
                 what=f"the final status {on_bus[-1]:#06x}")
    published = status_changes(cyclone.since(cyc_mark, "AxisStatus", NODE, 1))
    assert published == on_bus, f"bus: {seq_text(on_bus)}\nDDS: {seq_text(published)}"
    assert len(on_bus) >= 6, f"a homing and a move have more transitions than {seq_text(on_bus)}"


def test_a_master_remapping_a_tpdo_mid_run_is_followed(master, start_node, start_bridge, cyclone):
    start_bridge()
    link = boot(master, start_node)
    ax = link.axes[1]
    # The bridge discovers the node on the default SDO channel, which CiA 301 gives one client
    # at a time: the test's master waits until the bridge's transfers are over (its first
    # samples come before its last reads).
    wait_discovered(cyclone)
    wait_sdo_quiet(master)
    # A quadrature encoder with 1000 lines (counted once each) on 2000 steps/rev counts half
    # the motor's steps, so motor and encoder positions differ and a mix-up shows.
    master.write_u8(NODE, 0x2009, 1, 1)
    master.write_i32(NODE, 0x5001, 2, 1000)
    clear_and_profile(ax, FAST)
    set_position(ax, 0)
    # Swap TPDO2's entries by the CiA 301 procedure: encoder position first, then motor.
    cob = master.read_u32(NODE, 0x1801, 1)
    master.write_u32(NODE, 0x1801, 1, cob | 0x80000000)
    master.write_u8(NODE, 0x1A01, 0, 0)
    master.write_u32(NODE, 0x1A01, 1, 0x20060020)
    master.write_u32(NODE, 0x1A01, 2, 0x20050020)
    master.write_u8(NODE, 0x1A01, 0, 2)
    master.write_u32(NODE, 0x1801, 1, cob)
    time.sleep(1.0)  # the bridge re-reads the mapping once the master's SDO traffic is over
    mark, frames = cyclone.mark(), len(ax.position_log)
    ax.move("rel", 2000)
    cyclone.wait(lambda: any(s.int("motor_position") == 2000 for s in cyclone.since(mark, "AxisPosition", NODE, 1)),
                 what="AxisPosition 2000 decoded by the new mapping")
    # On the bus the first field is now the encoder (the link still reads it as "motor").
    link.pump(2.0, lambda: ax.position_log[-1].encoder == 2000)
    last = ax.position_log[-1]
    assert len(ax.position_log) > frames and (last.motor, last.encoder) == (1000, 2000), last
    # The bus frame was seen; its DDS sample may still be on its way to the subscriber.
    cyclone.wait(lambda: any((s.int("motor_position"), s.int("encoder_position")) == (2000, 1000)
                             for s in cyclone.since(mark, "AxisPosition", NODE, 1)),
                 what="the final AxisPosition (motor 2000, encoder 1000)")
    got = cyclone.since(mark, "AxisPosition", NODE, 1)
    end = [s for s in got if s.int("motor_position") == 2000][-1]
    assert end.int("encoder_position") == 1000, end.fields
    # A sample from TPDO1 (status + motor) carries the encoder of the last TPDO2, so the
    # encoder may lag; decoded the old way it would read twice the motor instead.
    pairs = [(s.int("motor_position"), s.int("encoder_position")) for s in got]
    assert all(2 * e <= m + 2 for m, e in pairs), pairs
