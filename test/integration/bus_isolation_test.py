#!/usr/bin/env python3
"""The onboard bus stays on the vehicle (docs/security.md), tested as an attacker on the network
would try it: two network namespaces joined by a veth pair, the vehicle in one, the attacker in
the other, which sends alight-attack's forged MOCAP_POSE to the bus.

  shipped   the vehicle's bus as the launch files keep it: ttl=0, the group routed via lo (as
            scripts/setup routes it), signed. The attacker's multicast never reaches the bus (the
            group is not joined on the veth); its unicast to the vehicle's port does (LCM's socket
            is bound to INADDR_ANY) and is refused by a signed node for being unsigned.
  insecure  the same vehicle with the group routed via the veth: the attacker's multicast reaches
            the bus. This shows the test can see what the route keeps out.

Needs root for network namespaces; without them it exits 77 (CTest: skipped).

    bus_isolation_test.py SOURCE_DIR BUILD_DIR
"""
import os
import random
import subprocess
import sys
import tempfile
import time

SRC, BUILD = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(SRC, "scripts"))
import lcmlog  # noqa: E402

GROUP = "239.255.76.67"
PORT = 7300 + random.randrange(0, 200)
URL = "udpm://%s:%d?ttl=0" % (GROUP, PORT)
TAG = "%d" % (os.getpid() % 100000)
VEH, ATT = "alight-veh-" + TAG, "alight-att-" + TAG
VETH_V, VETH_A = "alv" + TAG, "ala" + TAG
VEH_IP, ATT_IP = "10.231.77.1", "10.231.77.2"


def sh(*cmd, ns=None, check=True):
    full = (["ip", "netns", "exec", ns] if ns else []) + list(cmd)
    return subprocess.run(full, check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True)


def setup():
    sh("ip", "netns", "add", VEH)
    sh("ip", "netns", "add", ATT)
    sh("ip", "link", "add", VETH_V, "netns", VEH, "type", "veth", "peer", "name", VETH_A,
       "netns", ATT)
    for ns, dev, ip in ((VEH, VETH_V, VEH_IP), (ATT, VETH_A, ATT_IP)):
        sh("ip", "link", "set", "lo", "up", ns=ns)
        sh("ip", "link", "set", "lo", "multicast", "on", ns=ns)
        sh("ip", "addr", "add", ip + "/24", "dev", dev, ns=ns)
        sh("ip", "link", "set", dev, "up", ns=ns)
        sh("ip", "link", "set", dev, "multicast", "on", ns=ns)
    # The attacker's multicast goes out on its side of the wire.
    sh("ip", "route", "add", "224.0.0.0/4", "dev", VETH_A, ns=ATT)


def teardown():
    for ns in (VEH, ATT):
        subprocess.run(["ip", "netns", "del", ns], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)


def route_group(dev):
    sh("ip", "route", "replace", GROUP + "/32", "dev", dev, ns=VEH)


def attack(to):
    out = sh(os.path.join(BUILD, "bin", "alight-attack"), "--attack", "pose_ahead", "--to", to,
             "--listen-url", URL, ns=ATT)
    assert "1 datagrams sent" in out.stdout, out.stdout


def poses_logged(log):
    return sum(1 for ev in lcmlog.read_events(log) if ev.channel == "MOCAP_POSE")


def counters_at(log, node, channel):
    """The newest NODE_STATUS counters of `node` for `channel`: (received, rejected_auth)."""
    best = (0, 0)
    for ev in lcmlog.read_events(log, "NODE_STATUS"):
        m = lcmlog.decode(ev)
        if m is None or m.node != node:
            continue
        for c in m.channels:
            if c.channel == channel:
                best = (c.received, c.rejected_auth)
    return best


def run_vehicle(tmp, name, key):
    """lcm-logger and a signed alight-outer-loop on the vehicle's bus; returns (procs, log)."""
    log = os.path.join(tmp, name + ".lcmlog")
    logger = subprocess.Popen(["ip", "netns", "exec", VEH, "lcm-logger", "-q",
                               "--lcm-url=" + URL, log],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    node = subprocess.Popen(["ip", "netns", "exec", VEH, os.path.join(BUILD, "bin",
                                                                     "alight-outer-loop"),
                             "--config", os.path.join(SRC, "config", "vehicles", "pelican.yaml"),
                             "--lcm-url", URL, "--bus-key", key, "--state-file",
                             os.path.join(tmp, name + ".state"), "--log-level", "warn"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.5)  # both subscribed (generous: a loaded machine)
    return [logger, node], log


def stop(procs):
    time.sleep(2.5)  # a NODE_STATUS (1 Hz) after the attack
    for p in reversed(procs):
        p.terminate()
        p.wait(timeout=20)


def joined(ns):
    text = sh("cat", "/proc/net/igmp", ns=ns).stdout
    hexgroup = "%08X" % int.from_bytes(bytes(int(x) for x in GROUP.split(".")), "little")
    devs, dev = [], None
    for line in text.splitlines():
        if line and not line[0].isspace():
            parts = line.split()
            dev = parts[1] if len(parts) > 1 and parts[0] != "Idx" else dev
        elif line.split() and line.split()[0] == hexgroup:
            devs.append(dev)
    return devs


def main():
    if os.geteuid() != 0 or subprocess.run(["ip", "netns", "add", VEH + "-probe"],
                                           stderr=subprocess.DEVNULL).returncode != 0:
        print("SKIPPED: needs root and network namespaces (ip netns)")
        return 77
    subprocess.run(["ip", "netns", "del", VEH + "-probe"])
    failures = []
    with tempfile.TemporaryDirectory(prefix="alight-bus-isolation-") as tmp:
        key = os.path.join(tmp, "bus.key")
        subprocess.run([os.path.join(SRC, "scripts", "make-key"), key], check=True,
                       stdout=subprocess.DEVNULL)
        try:
            setup()
            # Shipped: the group via lo.
            route_group("lo")
            procs, log = run_vehicle(tmp, "shipped_multicast", key)
            print("shipped: group joined on", joined(VEH))
            if any(d != "lo" for d in joined(VEH)):
                failures.append("shipped: the group is joined on %s" % joined(VEH))
            attack("%s:%d" % (GROUP, PORT))
            stop(procs)
            n = poses_logged(log)
            print("shipped, attacker's multicast: %d forged poses on the vehicle's bus" % n)
            if n != 0:
                failures.append("shipped: the attacker's multicast reached the bus")
            procs, log = run_vehicle(tmp, "shipped_unicast", key)
            attack("%s:%d" % (VEH_IP, PORT))
            stop(procs)
            # A unicast datagram goes to one of the sockets bound to the port (the newest): here
            # the outer loop's, else the logger's.
            n = poses_logged(log)
            received, auth = counters_at(log, "alight-outer-loop", "MOCAP_POSE")
            print("shipped, attacker's unicast: the logger took %d, the signed outer loop refused "
                  "%d for their origin and accepted %d" % (n, auth, received))
            if n + auth < 1:
                failures.append("shipped: the unicast reached no socket (the test cannot tell "
                                "refused from lost)")
            if received != 0:
                failures.append("shipped: the signed node accepted an unsigned pose")
            # Insecure: the group via the veth.
            route_group(VETH_V)
            procs, log = run_vehicle(tmp, "insecure", key)
            print("insecure: group joined on", joined(VEH))
            attack("%s:%d" % (GROUP, PORT))
            stop(procs)
            n = poses_logged(log)
            print("insecure, attacker's multicast: %d forged poses on the vehicle's bus" % n)
            if n < 1:
                failures.append("insecure: the attacker's multicast did not arrive (the test "
                                "cannot tell a routed group from a broken setup)")
        finally:
            teardown()
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
