"""CiA 305 activate bit timing carried out by the node (--apply-bit-timing): after the
command the node sends nothing for twice the switch delay (once before the controller
switches, once after), then goes on. vcan has no bit rate, so the switch itself is refused
(the link is left up) and logged; the silence is the part a master on any bus sees."""

import time

from conftest import open_bus
from lss_master import MODE_CONFIGURATION, MODE_WAITING, LssMaster

NODE = 0x31
DELAY_MS = 200


def test_the_node_is_silent_for_two_switch_delays_then_goes_on(master, start_node, tmp_path):
    cfg = tmp_path / "hb.toml"
    cfg.write_text('apply_bit_timing = true\n[defaults]\n"1017" = 20\n')  # heartbeat every 20 ms
    node = start_node(NODE, ["--config", str(cfg)])
    bus = open_bus()
    try:
        lss = LssMaster(bus)
        lss.switch_state_global(MODE_CONFIGURATION)
        assert lss.configure_bit_timing(2) == 0  # CiA 305 table 0 index 2: 500 kbit/s
        master.flush()
        sent_at = time.time()
        lss.activate_bit_timing(DELAY_MS)
        frames = master.collect(1.2, lambda m: m.arbitration_id == 0x700 + NODE)
        lss.switch_state_global(MODE_WAITING)
    finally:
        bus.shutdown()
    after = [m.timestamp - sent_at for m in frames]
    # The node handled the command no earlier than it was sent: nothing from it until 2 x the
    # delay after that (a margin of 20 ms for a heartbeat the node sent before it read the
    # command), then its 20 ms heartbeat again.
    quiet = [a for a in after if 0.02 < a < 2 * DELAY_MS / 1000]
    assert quiet == [], (after, node.log())
    assert len([a for a in after if a >= 2 * DELAY_MS / 1000]) >= 10, (after, node.log())
    log = node.log()
    assert "activate bit timing 500 kbit/s: switching in 200 ms, silent for 400 ms" in log, log
    assert "the bit timing 500 kbit/s was not applied: vcan0: not a CAN controller" in log, log
    assert "Network is down" not in log, log
    assert "frames made during the bit timing switch were not sent" in log, log
