"""The bridge beside other vendors' devices (issue 5): a device that is not a stepnode is
still listed in NodeHealth with its NMT state, and has no axes."""

from __future__ import annotations

from axis_helpers import HeartbeatSender
from bridge_helpers import DDS_TIMEOUT, domain, node_line, start_bridge, stepbridge_bin, stepwatch_bin, wait_for_snapshot

_ = (domain, start_bridge, stepbridge_bin)  # fixtures


def node_row(lines, node) -> dict:
    """The node's line, or {} while there is none."""
    return node_line(lines, node) or {}


def test_a_device_that_is_not_a_stepnode_is_listed_with_its_state(master, start_bridge, stepwatch_bin, domain):
    start_bridge()
    other = 0x33
    # A device that answers no SDO at all (a simple I/O module, say): a boot-up, then
    # heartbeats. It is listed, as no stepnode and with no axes.
    master.send(0x700 + other, b"\x00")
    beat = HeartbeatSender(node=other, period=0.2).start()
    try:
        rows = wait_for_snapshot(stepwatch_bin, domain, lambda r: node_row(r, other).get("state") == "OPERATIONAL",
                                 timeout=DDS_TIMEOUT)
        n = node_row(rows, other)
        assert not n["is_stepnode"] and not [l for l in rows if l["type"] == "axis" and l["node"] == other], n
        # Its discovery fails over and over: counted (and retried), never fatal.
        wait_for_snapshot(stepwatch_bin, domain, lambda r: node_row(r, other).get("sdo_failures", 0) >= 1,
                          timeout=DDS_TIMEOUT)
    finally:
        beat.close()
    wait_for_snapshot(stepwatch_bin, domain, lambda r: node_row(r, other).get("state") == "LOST", timeout=DDS_TIMEOUT)
