"""stepnode given bad input on its command line or in its config file: exit status 2 and
exactly one line on stderr that names the problem (DESIGN.md, conventions). Nothing is
sent on the bus."""

import subprocess

import pytest

from conftest import CHANNEL


def run_node(stepnode_bin, args, cwd):
    return subprocess.run([str(stepnode_bin), *map(str, args)], capture_output=True, text=True, timeout=20,
                          cwd=str(cwd), stdin=subprocess.DEVNULL)


def config(tmp_path, text):
    path = tmp_path / "node.toml"
    path.write_text(text)
    return path


CASES = {
    "node id 0": (lambda t: ["--iface", CHANNEL, "--node-id", "0"], "--node-id 0"),
    "node id 128": (lambda t: ["--iface", CHANNEL, "--node-id", "128"], "--node-id 128"),
    "node id not a number": (lambda t: ["--iface", CHANNEL, "--node-id", "five"], "five"),
    "missing --iface": (lambda t: ["--node-id", "5", "--state-dir", t], "--iface"),
    "missing --node-id": (lambda t: ["--iface", CHANNEL, "--state-dir", t], "--node-id"),
    "nonexistent interface": (lambda t: ["--iface", "nosuch0", "--node-id", "5", "--state-dir", t], "nosuch0"),
    "not a CAN interface": (lambda t: ["--iface", "lo", "--node-id", "5", "--state-dir", t], "lo"),
    "unknown option": (lambda t: ["--iface", CHANNEL, "--node-id", "5", "--speed", "9"], "--speed"),
    "config file missing": (lambda t: ["--iface", CHANNEL, "--node-id", "5", "--config", t / "none.toml"],
                            "none.toml"),
    "config is a directory": (lambda t: ["--iface", CHANNEL, "--node-id", "5", "--config", t], "cannot read"),
    "config not TOML": (lambda t: ["--iface", CHANNEL, "--config", config(t, "node_id = = 5\n")], "node.toml"),
    "config node id 300": (lambda t: ["--iface", CHANNEL, "--config", config(t, "node_id = 300\n")], "node_id"),
    "config default of a read-only object": (
        lambda t: ["--iface", CHANNEL, "--node-id", "5", "--state-dir", t,
                   "--config", config(t, '[defaults]\n"1000" = 1\n')], "1000"),
    "config default above the limit": (
        lambda t: ["--iface", CHANNEL, "--node-id", "5", "--state-dir", t,
                   "--config", config(t, '[defaults]\n"1800:6" = 241\n')], "1800:6"),
    "config default does not fit the type": (
        lambda t: ["--iface", CHANNEL, "--node-id", "5", "--state-dir", t,
                   "--config", config(t, '[defaults]\n"1017" = 70000\n')], "1017"),
    "config default of a missing object": (
        lambda t: ["--iface", CHANNEL, "--node-id", "5", "--state-dir", t,
                   "--config", config(t, '[defaults]\n"4321" = 1\n')], "4321"),
    "tick out of range": (lambda t: ["--iface", CHANNEL, "--node-id", "5", "--tick-us", "5"], "--tick-us"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_exits_2_with_one_line(stepnode_bin, tmp_path, bus, case):
    make_args, named = CASES[case]
    r = run_node(stepnode_bin, make_args(tmp_path), tmp_path)
    lines = r.stderr.splitlines()
    assert r.returncode == 2, f"exit status {r.returncode}, stderr {r.stderr!r}, stdout {r.stdout!r}"
    assert len(lines) == 1 and lines[0].strip(), f"stderr is not one line: {r.stderr!r}"
    assert lines[0].startswith("stepnode: "), lines[0]
    assert named in lines[0], f"the line does not name {named!r}: {lines[0]}"
    assert r.stdout == "", r.stdout
    # The node never came up: no boot-up frame (nor anything else) on the bus.
    assert bus.recv(timeout=0.2) is None


def test_a_runtime_failure_exits_1_with_one_line(stepnode_bin, tmp_path, bus):
    """Good arguments, but the process runs out of file descriptors: the limit leaves one
    beyond stdin, stdout and stderr, taken by the CAN socket, so looking the interface up
    fails. A runtime failure, not bad input ("no such interface"): status 1, one line."""
    import resource

    def few_descriptors():
        resource.setrlimit(resource.RLIMIT_NOFILE, (4, 4))

    r = subprocess.run([str(stepnode_bin), "--iface", CHANNEL, "--node-id", "5", "--state-dir", str(tmp_path)],
                       capture_output=True, text=True, timeout=20, cwd=str(tmp_path), stdin=subprocess.DEVNULL,
                       preexec_fn=few_descriptors)
    lines = r.stderr.splitlines()
    assert r.returncode == 1, f"exit status {r.returncode}, stderr {r.stderr!r}"
    assert len(lines) == 1 and lines[0].startswith(f"stepnode: {CHANNEL}: "), r.stderr
    assert bus.recv(timeout=0.2) is None  # no boot-up: the node never came up


def test_help_and_print_eds_exit_0(stepnode_bin, tmp_path):
    r = run_node(stepnode_bin, ["--help"], tmp_path)
    assert r.returncode == 0 and "--node-id" in r.stdout and "--iface" in r.stdout
    r = run_node(stepnode_bin, ["--print-eds"], tmp_path)
    assert r.returncode == 0 and r.stdout.startswith("[FileInfo]") and r.stderr == ""


def test_node_id_from_the_config_file(start_node, stepnode_bin, tmp_path, master):
    """The config file may set the node id; the command line wins over it."""
    path = config(tmp_path, "node_id = 9\n")
    node = start_node(9, ["--config", path])  # the fixture passes --node-id 9 too
    assert master.read_u32(9, 0x1200, 1) == 0x609
    node.kill()
    master.flush()
    proc = subprocess.Popen([str(stepnode_bin), "--iface", CHANNEL, "--config", str(path), "--state-dir",
                             str(tmp_path)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            cwd=str(tmp_path))
    try:
        assert master.wait_bootup(9, timeout=15) is not None, "no boot-up of node 9 (id from the file)"
        assert master.read_u32(9, 0x1200, 2) == 0x589
    finally:
        proc.kill()
        proc.wait()
