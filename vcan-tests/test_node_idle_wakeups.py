"""Event-driven timing on vcan (issue 13): an idle node sleeps until its next deadline. The
node's voluntary context switches (/proc/PID/status: each is the process going to sleep in
epoll_wait and being woken) and its CPU ticks (/proc/PID/stat utime + stime) are counted
over a few seconds. Before issue 13 the 1 ms timerfd woke it about 1000 times a second
whatever there was to do. The bounds are generous on purpose (UML schedules coarsely); the
figures are printed for the README, never compared with each other."""

import os
import time

CLK_TCK = os.sysconf("SC_CLK_TCK")
NODE = 21
SECONDS = 4.0


def wakeups_and_cpu(pid):
    with open(f"/proc/{pid}/status") as f:
        switches = next(int(l.split()[1]) for l in f if l.startswith("voluntary_ctxt_switches"))
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return switches, int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15)


def measure(pid, seconds=SECONDS):
    w0, c0 = wakeups_and_cpu(pid)
    time.sleep(seconds)
    w1, c1 = wakeups_and_cpu(pid)
    return (w1 - w0) / seconds, 100.0 * (c1 - c0) / CLK_TCK / seconds


def test_an_idle_node_wakes_for_its_heartbeat_only(master, start_node):
    node = start_node(NODE)
    master.write_u16(NODE, 0x1017, 0, 100)  # heartbeat every 100 ms: 10 wake-ups a second
    time.sleep(0.5)
    rate, cpu = measure(node.proc.pid)
    print(f"\nidle, heartbeat 100 ms: {rate:.1f} wake-ups/s, CPU {cpu:.2f} % of a core")
    assert rate < 50, f"{rate:.1f} wake-ups per second idle with a 100 ms heartbeat"
    master.write_u16(NODE, 0x1017, 0, 0)  # no heartbeat: nothing timed at all
    time.sleep(0.5)
    rate, cpu = measure(node.proc.pid)
    print(f"idle, no heartbeat: {rate:.1f} wake-ups/s, CPU {cpu:.2f} % of a core")
    assert rate < 20, f"{rate:.1f} wake-ups per second idle without a heartbeat"
    assert node.alive
