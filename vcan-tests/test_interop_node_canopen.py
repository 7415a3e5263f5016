"""Interoperability: a third-party CANopen master (node-canopen, npm "canopen", with the
npm "socketcan" transport) drives a stepnode over vcan.

The master is vcan-tests/interop/master.js (CiA 301: NMT, SDO, PDO, SYNC, heartbeat, EMCY,
EDS) and, for a node with `profiles = ["cia402"]`, vcan-tests/interop/cia402.js (the CiA 402
state machine and profile position mode through node-canopen's SDO and PDO); each prints
one line per check and exits non-zero at the first failure with the frames of that check.
Their npm packages are installed into vcan-tests/interop/node_modules by tools/setup (npm
ci); without them these tests fail instead of skipping, so CI cannot silently lose them.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from conftest import CHANNEL, REPO_ROOT

INTEROP = REPO_ROOT / "vcan-tests" / "interop"
NODE_ID = 9
# node under User-Mode Linux is slow: the session takes ~10 s natively, allow far more.
TIMEOUT = float(os.environ.get("INTEROP_TIMEOUT", "300"))


def node_binary() -> str:
    for cand in ("/usr/bin/node", shutil.which("node"), shutil.which("nodejs")):
        if cand and os.access(cand, os.X_OK):
            return cand
    pytest.fail("node (Node.js) is not installed: run tools/setup (installs Debian's nodejs and npm)",
                pytrace=False)


def run_master(script: str, args, node) -> str:
    """Runs the node-canopen script `script` (in vcan-tests/interop) with `args` against the
    running `node`; fails the test unless it exits 0 with the node alive. Returns its output."""
    modules = INTEROP / "node_modules"
    if not (modules / "canopen").is_dir() or not (modules / "socketcan").is_dir():
        pytest.fail(f"{modules} is missing (node-canopen and socketcan): run tools/setup "
                    "(it runs `npm ci` in vcan-tests/interop)", pytrace=False)
    argv = [node_binary(), str(INTEROP / script), "--iface", CHANNEL, *map(str, args)]
    t0 = time.monotonic()
    try:
        proc = subprocess.run(argv, cwd=str(INTEROP), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=TIMEOUT + 30)
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode(errors="replace")
        pytest.fail(f"{script} did not finish within {TIMEOUT + 30:.0f} s\n$ {' '.join(argv)}\n{out}\n"
                    f"--- stepnode log ---\n{node.log()[-4000:]}", pytrace=False)
    took = time.monotonic() - t0
    out = proc.stdout.decode(errors="replace")
    print(f"$ {' '.join(argv)}\n{out}({script}: exit {proc.returncode} after {took:.1f} s)")
    assert proc.returncode == 0, (
        f"node-canopen session {script} failed (exit {proc.returncode} after {took:.1f} s):\n{out}\n"
        f"--- stepnode log ---\n{node.log()[-4000:]}")
    assert node.alive, f"stepnode exited during the session (status {node.returncode})"
    return out


def test_node_canopen_master_drives_stepnode(start_node, tmp_path):
    node = start_node(NODE_ID)
    eds_out = tmp_path / f"node{NODE_ID}-from-sdo.eds"
    out = run_master("master.js", ["--node", NODE_ID, "--eds-out", eds_out, "--timeout", int(TIMEOUT)], node)
    assert "all " in out and " checks passed" in out, out
    # The EDS the node served by block transfer is the one this build prints.
    text = eds_out.read_text(errors="replace")
    assert text.startswith("[FileInfo]"), text[:200]
    printed = subprocess.run([str(node.argv[0]), "--print-eds"], stdout=subprocess.PIPE, timeout=60,
                             check=True).stdout.decode(errors="replace")
    assert text == printed, "the EDS read from 0x1021 differs from `stepnode --print-eds`"


CIA402_NODE_ID = 10


def test_node_canopen_master_drives_a_cia402_axis(start_node, tmp_path):
    """node-canopen drives axis 1 of a `profiles = ["cia402"]` node (vcan-tests/interop/cia402.js):
    controlword 06h/07h/0Fh over SDO with 6041h read at each step and decoded with CiA
    402's masks (and seen in the node's TPDO1 by node-canopen's PDO consumer), then two pp
    moves with the set-point handshake, target reached and 6064h."""
    config = tmp_path / "cia402.toml"
    config.write_text('axes = 1\nprofiles = ["cia402"]\n')
    node = start_node(CIA402_NODE_ID, ["--config", config])
    out = run_master("cia402.js", ["--node", CIA402_NODE_ID, "--timeout", int(TIMEOUT)], node)
    assert "all " in out and " checks passed" in out, out
    passed = [line for line in out.splitlines() if line.startswith("ok   ")]
    for step in ("-> Ready to switch on", "-> Switched on", "-> Operation enabled", "pp absolute", "pp relative"):
        assert any(step in line for line in passed), f"no passed check about {step!r} in:\n{out}"


LSS_NODE_ID = 11
LSS_SERIAL = 0x5EED0B0B


def test_node_canopen_lss_master_and_a_second_sdo_channel(start_node):
    """node-canopen's LSS master (CiA 305) fast-scans a node started without a node-ID, gives
    it one and stores it; then node-canopen's SDO client configures the node's SDO server
    channel 2 (0x1201) over the default one and reads over both at once, each answer on its
    own COB-ID (vcan-tests/interop/lss_channels.js)."""
    node = start_node("none", ["--serial-number", hex(LSS_SERIAL)], wait_bootup=False)
    out = run_master("lss_channels.js", ["--serial", LSS_SERIAL, "--node", LSS_NODE_ID], node)
    assert out.count("ok   ") == 5 and "FAIL" not in out, out
