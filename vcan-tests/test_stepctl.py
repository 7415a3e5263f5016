"""stepctl (the master CLI) against a running stepnode on vcan: typed read/write, NMT with
confirmation, block read of the EDS to a file, dump, exit statuses and one-line errors,
and `watch` decoding live traffic (NMT, heartbeat, SYNC, EMCY, TPDO by mapping).

Every value stepctl reports is checked against the node through the independent python
master (canopen_master.py), and vice versa."""

import os
import queue
import re
import subprocess
import threading
import time

import pytest

from canopen_master import STATE_OPERATIONAL, STATE_PREOPERATIONAL, STATE_STOPPED
from conftest import CHANNEL

NODE = 5


@pytest.fixture
def stepctl(stepctl_bin, tmp_path):
    def run(*args, timeout=60):
        return subprocess.run([str(stepctl_bin), "--iface", CHANNEL, *map(str, args)], capture_output=True,
                              text=True, timeout=timeout, cwd=str(tmp_path), stdin=subprocess.DEVNULL)
    return run


def one_error_line(r):
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("stepctl: "), f"stderr: {r.stderr!r}"
    return lines[0]


# ---------------------------------------------------------------- read / write


def test_read_prints_the_typed_value(stepctl, start_node):
    start_node(NODE)
    r = stepctl("read", NODE, "0x1008")
    assert r.returncode == 0, r.stderr
    assert r.stdout == '0x1008:00 Manufacturer device name = "stepnode" (VISIBLE_STRING)\n'
    r = stepctl("read", NODE, "0x1017")
    assert r.returncode == 0 and r.stdout == "0x1017:00 Producer heartbeat time = 1000 (UNSIGNED16)\n", r
    r = stepctl("read", NODE, "0x1018:2")
    assert r.returncode == 0 and r.stdout == "0x1018:02 Identity object / Product code = 0x53544550 (UNSIGNED32)\n", r
    r = stepctl("read", NODE, "0x2F00:1")
    assert r.returncode == 0 and r.stdout.startswith("0x2F00:01 User registers / User register 1 = 0 "), r


def test_write_then_read_back(stepctl, master, start_node, tmp_path):
    start_node(NODE)
    r = stepctl("write", NODE, "0x1017", "250")
    assert r.returncode == 0, r.stderr
    assert "250" in r.stdout and "written" in r.stdout
    r = stepctl("read", NODE, "0x1017")
    assert r.stdout == "0x1017:00 Producer heartbeat time = 250 (UNSIGNED16)\n", r
    master.flush()  # stepctl's SDO frames are in this master's socket too
    assert master.read_u16(NODE, 0x1017) == 250
    # Hex input, a 32-bit register, and a DOMAIN from a file by block transfer.
    assert stepctl("write", NODE, "0x2F00:3", "0xDEADBEEF").returncode == 0
    master.flush()
    assert master.read_u32(NODE, 0x2F00, 3) == 0xDEADBEEF
    blob = os.urandom(3000)
    path = tmp_path / "blob.bin"
    path.write_bytes(blob)
    r = stepctl("write", NODE, "0x2F01", f"@{path}", "--block")
    assert r.returncode == 0, r.stderr
    master.flush()
    assert master.sdo_upload(NODE, 0x2F01, 0) == blob


def test_read_eds_by_block_to_a_file(stepctl, start_node, stepnode_bin, tmp_path):
    start_node(NODE)
    out = tmp_path / "node5.eds"
    r = stepctl("read", NODE, "0x1021", "--block", "--output", out)
    assert r.returncode == 0, r.stderr
    printed = subprocess.run([str(stepnode_bin), "--print-eds"], capture_output=True, check=True, timeout=60).stdout
    data = out.read_bytes()
    assert data.startswith(b"[FileInfo]") and len(data) > 50_000
    assert data == printed
    assert f"{len(data)} bytes written to {out}" in r.stdout


# ---------------------------------------------------------------- nmt


def test_nmt_commands_are_confirmed(stepctl, master, start_node):
    start_node(NODE)
    for command, state, text in (("start", STATE_OPERATIONAL, "node 5: start confirmed"),
                                 ("stop", STATE_STOPPED, "node 5: stop confirmed"),
                                 ("preop", STATE_PREOPERATIONAL, "node 5: preop confirmed"),
                                 ("reset-node", 0x00, "node 5: boot-up after reset-node"),
                                 ("reset-comm", 0x00, "node 5: boot-up after reset-comm")):
        master.flush()
        r = stepctl("nmt", command, "--node", NODE)
        assert r.returncode == 0 and r.stdout.strip() == text, (command, r)
        assert master.wait_heartbeat(NODE, timeout=2.0, state=state) == state, command
    # Broadcast: not confirmable, but it reaches the node.
    master.flush()
    r = stepctl("nmt", "start", "--node", 0)
    assert r.returncode == 0 and "all nodes" in r.stdout
    assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
    # No such node: no confirmation, exit 1 with one line.
    r = stepctl("--timeout", 500, "nmt", "start", "--node", 44)
    assert r.returncode == 1 and "node 44" in one_error_line(r)


# ---------------------------------------------------------------- errors


def test_refused_write_exits_1_naming_the_abort(stepctl, master, start_node):
    start_node(NODE)
    r = stepctl("write", NODE, "0x1000", "1")
    assert r.returncode == 1
    line = one_error_line(r)
    assert "0x06010002" in line and "0x1000" in line, line
    r = stepctl("read", NODE, "0x1F00")
    assert r.returncode == 1 and "0x06020000" in one_error_line(r)
    r = stepctl("read", NODE, "0x1018:9")
    assert r.returncode == 1 and "0x06090011" in one_error_line(r)
    r = stepctl("write", NODE, "0x1010:1", "0x12345678")
    assert r.returncode == 1 and "0x08000020" in one_error_line(r)
    # Nobody answers: a timeout, exit 1.
    r = stepctl("--timeout", 300, "read", 44, "0x1000")
    assert r.returncode == 1 and "0x05040000" in one_error_line(r)
    master.flush()
    assert master.read_u32(NODE, 0x1000) == 0


@pytest.mark.parametrize("args", [("read", NODE, "zz"), ("read", NODE, "0x1017:xyz"), ("read", NODE, "0x123456"),
                                  ("read", 0, "0x1000"), ("read", 128, "0x1000"), ("write", NODE, "0x1017", "many"),
                                  ("write", NODE, "0x1017", "70000"), ("write", NODE, "0x4321", "1"),
                                  ("nmt", "jump", "--node", NODE), ("frobnicate",)])
def test_bad_input_exits_2_with_one_line(stepctl, start_node, master, args):
    start_node(NODE)
    master.flush()
    r = stepctl(*args)
    assert r.returncode == 2, r
    one_error_line(r)
    # Nothing was sent to the node.
    assert master.collect(0.3, lambda m: m.arbitration_id in (0x600 + NODE, 0x000)) == []


# ---------------------------------------------------------------- dump


def test_dump_lists_every_object(stepctl, start_node, master):
    start_node(NODE)
    master.write_u32(NODE, 0x2F00, 7, 0x77)
    r = stepctl("dump", NODE, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    lines = r.stdout.splitlines()
    assert "0x1018:02 Identity object / Product code = 0x53544550 (UNSIGNED32)" in lines
    assert '0x1008:00 Manufacturer device name = "stepnode" (VISIBLE_STRING)' in lines
    assert "0x1017:00 Producer heartbeat time = 1000 (UNSIGNED16)" in lines
    assert any(line.startswith("0x2F00:07 User registers / User register 7 = 119") for line in lines), \
        [line for line in lines if line.startswith("0x2F00")]
    for needed in ("0x1000:00", "0x1001:00", "0x1018:01", "0x1018:03", "0x1018:04", "0x1A00:01", "0x1400:01"):
        assert any(line.startswith(needed + " ") for line in lines), needed
    assert len(lines) > 200


# ---------------------------------------------------------------- watch


class Watch:
    """`stepctl watch` as a subprocess; its lines are read by a thread into a queue."""

    def __init__(self, stepctl_bin, seconds):
        self.proc = subprocess.Popen([str(stepctl_bin), "--iface", CHANNEL, "watch", "--seconds", str(seconds)],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     stdin=subprocess.DEVNULL)
        self.lines = []
        self.queue = queue.Queue()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self.queue.put(line.rstrip("\n"))
        self.queue.put(None)

    def wait_line(self, pattern, timeout):
        """The first line (from now on, or already seen) matching the regex pattern."""
        for line in self.lines:
            if re.search(pattern, line):
                return line
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = self.queue.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                return None
            if line is None:
                return None
            self.lines.append(line)
            if re.search(pattern, line):
                return line
        return None

    def finish(self, timeout=60):
        self.proc.wait(timeout)
        self.reader.join(10)
        while not self.queue.empty():
            line = self.queue.get()
            if line is not None:
                self.lines.append(line)
        return self.proc.returncode


def test_watch_decodes_live_traffic(stepctl_bin, master, start_node):
    start_node(NODE)
    # TPDO1: user register 1 (event-driven) before the watch starts.
    master.write_u32(NODE, 0x1800, 1, 0x80000180 + NODE)
    master.write_u8(NODE, 0x1A00, 0, 0)
    master.write_u32(NODE, 0x1A00, 1, 0x2F000120)
    master.write_u8(NODE, 0x1A00, 0, 1)
    master.write_u32(NODE, 0x1800, 1, 0x40000180 + NODE)
    master.write_u16(NODE, 0x1017, 0, 300)
    watch = Watch(stepctl_bin, seconds=20)
    try:
        # The watch is ready when it prints the frames it sees (python and the tool start
        # slowly in User-Mode Linux): send SYNCs until one shows up.
        deadline = time.monotonic() + 15
        while watch.wait_line(r"\b080 \[0\] .*SYNC$", 0.3) is None:
            assert time.monotonic() < deadline, f"stepctl watch printed no SYNC: {watch.lines}"
            master.sync()
        # It reads the node's mapping over SDO when it sees the node's heartbeat.
        assert watch.wait_line(rf"read the mapping of node {NODE}'s \d+ valid PDOs", 5), watch.lines
        master.flush()
        master.nmt_start(NODE)
        assert master.wait_heartbeat(NODE, timeout=2.0, state=STATE_OPERATIONAL) == STATE_OPERATIONAL
        assert watch.wait_line(rf"NMT start node {NODE}$", 5), watch.lines
        assert watch.wait_line(rf"heartbeat node {NODE}: operational$", 5), watch.lines
        # The TPDO goes out on entering operational and on a change; decoded by name.
        time.sleep(0.5)  # the SDO channel must be quiet for the watch's own reads
        master.write_u32(NODE, 0x2F00, 1, 0x12345678)
        line = watch.wait_line(rf"TPDO1 node {NODE}: User registers / User register 1 = 305419896$", 5)
        assert line and line.split()[1] == f"{0x180 + NODE:03X}", "\n".join(watch.lines)
        # EMCY: the node watches node 126 (300 ms), which beats once and falls silent.
        master.write_u32(NODE, 0x1016, 1, (0x7E << 16) | 300)
        master.send(0x77E, b"\x05")
        assert master.wait_emcy(NODE, timeout=2.0) is not None
        line = watch.wait_line(rf"EMCY node {NODE}: 0x8130 ", 5)
        assert line and "life guard or heartbeat error" in line and "error register 0x11" in line, line
        assert watch.wait_line(r"heartbeat node 126: operational$", 1), watch.lines
        # SDO traffic of another master is decoded too.
        master.flush()
        master.read_u16(NODE, 0x1017)
        assert watch.wait_line(rf"SDO node {NODE} request: upload 0x1017:00 Producer heartbeat time$", 5)
        assert watch.wait_line(rf"SDO node {NODE} response: upload 0x1017:00 Producer heartbeat time = 2c 01$", 5)
    finally:
        watch.proc.terminate()
        watch.finish()
    assert watch.proc.stderr.read() == ""


def test_watch_ends_after_seconds(stepctl_bin):
    t0 = time.monotonic()
    watch = Watch(stepctl_bin, seconds=2)
    assert watch.finish(timeout=30) == 0
    elapsed = time.monotonic() - t0
    assert 2.0 <= elapsed < 15, elapsed
