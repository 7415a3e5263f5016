"""DDS Security end to end (issue 14, README "DDS Security"): a node on vcan0, stepbridge
with the [dds.security] table of tools/dds-security-certs, and stepwatch processes: the
permitted supervisor sees the node, a stepwatch without security and one with a valid
certificate but permissions signed by another CA see nothing; a wrong file stops the
bridge at start with one line (status 2)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import List, Tuple

import pytest

from axis_helpers import NODE, boot
from bridge_helpers import domain, node_line, start_bridge, stepbridge_bin, stepwatch_bin, wait_for_snapshot
from conftest import CHANNEL

_ = (domain, start_bridge, stepbridge_bin, stepwatch_bin)  # fixtures

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def pki(tmp_path) -> Path:
    d = tmp_path / "pki"
    r = subprocess.run([str(ROOT / "tools/dds-security-certs"), str(d), "--with-intruder", "--days", "2"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return d


def watch(stepwatch_bin: Path, domain: int, *extra: str, wait_ms: int = 4000) -> Tuple[int, List[dict]]:
    """stepwatch --once --json; Fast DDS's own log lines on stdout (a refused peer) are skipped."""
    r = subprocess.run([str(stepwatch_bin), "--once", "--json", "--domain", str(domain), "--wait-ms", str(wait_ms),
                        *extra], capture_output=True, text=True, timeout=wait_ms / 1000 + 15)
    return r.returncode, [json.loads(l) for l in r.stdout.splitlines() if l.startswith("{")]


def test_only_the_permitted_supervisor_reads_the_bridge(master, start_node, start_bridge, stepwatch_bin, domain, pki):
    start_bridge("--config", pki / "stepbridge.toml")
    boot(master, start_node, NODE)
    supervisor = ("--security-config", str(pki / "supervisor.toml"))
    lines = wait_for_snapshot(stepwatch_bin, domain,
                              lambda ls: bool(node_line(ls, NODE) and node_line(ls, NODE)["state"] == "OPERATIONAL"),
                              timeout=30.0, extra=supervisor)
    assert node_line(lines, NODE)["state"] == "OPERATIONAL"

    status, lines = watch(stepwatch_bin, domain)
    assert (status, lines) == (1, []), "a stepwatch without DDS Security read the bridge"
    status, lines = watch(stepwatch_bin, domain, "--security-config", str(pki / "intruder.toml"))
    assert (status, lines) == (1, []), "a stepwatch with another CA's permissions read the bridge"


def test_a_wrong_security_file_is_one_line_at_start(stepbridge_bin, domain, pki):
    bad = pki / "bad-bridge.toml"
    bad.write_text((pki / "stepbridge.toml").read_text().replace('"stepbridge/key.pem"', '"supervisor/key.pem"'))
    r = subprocess.run([str(stepbridge_bin), "--iface", CHANNEL, "--domain", str(domain), "--config", str(bad)],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 2
    assert r.stderr.splitlines() == [
        f"stepbridge: dds.security.private_key {pki}/supervisor/key.pem: is not the key of identity_certificate "
        f"{pki}/stepbridge/cert.pem"]
