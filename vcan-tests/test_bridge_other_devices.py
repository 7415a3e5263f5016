"""The bridge beside other vendors' devices (issue 5): a device that is not a stepnode is
still listed in NodeHealth with its NMT state, and has no axes."""

from __future__ import annotations

import time

from axis_helpers import HeartbeatSender
from bridge_helpers import DDS_TIMEOUT, domain, start_bridge, stepwatch_once

_ = (domain, start_bridge)  # fixtures


def node_row(rows, node) -> dict:
    """The node's row, or {} while there is none."""
    return next((r for r in rows if r.get("type") == "node" and r["node"] == node), {})


def axis_rows(rows, node):
    return [r for r in rows if r.get("type") == "axis" and r["node"] == node]


def wait_rows(domain, pred, what, timeout=DDS_TIMEOUT):
    deadline = time.monotonic() + timeout
    rows = []
    while time.monotonic() < deadline:
        rows = stepwatch_once(domain, wait_ms=2000, allow_empty=True)
        if pred(rows):
            return rows
        time.sleep(0.3)
    raise AssertionError(f"stepwatch: {what} not seen within {timeout} s; last rows: {rows}")


def test_a_device_that_is_not_a_stepnode_is_listed_with_its_state(master, start_bridge, domain):
    start_bridge()
    other = 0x33
    # A device that answers no SDO at all (a simple I/O module, say): a boot-up, then
    # heartbeats. It is listed, as no stepnode and with no axes; its discovery failing over
    # and over is counted, never fatal.
    master.send(0x700 + other, b"\x00")
    beat = HeartbeatSender(node=other, period=0.2).start()
    try:
        rows = wait_rows(domain, lambda r: node_row(r, other).get("state") == "OPERATIONAL",
                         f"node {other} OPERATIONAL")
        n = node_row(rows, other)
        assert not n["is_stepnode"] and not axis_rows(rows, other), n
        rows = wait_rows(domain, lambda r: node_row(r, other).get("sdo_failures", 0) >= 1, "an SDO failure counted")
    finally:
        beat.close()
    rows = wait_rows(domain, lambda r: node_row(r, other).get("state") == "LOST", f"node {other} LOST")
