"""scripts/replay-estimator's bookkeeping without a flight or a network: where the live node
started (its first estimate counts the IMU samples it had received), which input losses in the log
stop the comparison, and that a single changed byte is found.
Usage: replay_estimator_test.py SCRIPTS_DIR"""
import os
import struct
import sys

import script_module

scripts = sys.argv[1]
sys.path.insert(0, scripts)
re_ = script_module.load(scripts, "replay-estimator")
import lcmlog  # noqa: E402

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)


def msg(channel, utime, seq=0, tail=b""):
    """An input or estimate payload as far as replay-estimator reads it: fingerprint, utime, seq."""
    return lcmlog.Event(0, utime, channel, b"F" * 8 + struct.pack(">qq", utime, seq) + tail)


def session(imu_seqs, frames=(), estimates=()):
    """IMU every 5 ms (seq -> utime 5000 * seq), RANGE with each tenth, frames at given stamps,
    estimates at given IMU seqs, all in stamp order."""
    evs = [msg("IMU", 5000 * s, s) for s in imu_seqs]
    evs += [msg("RANGE", 5000 * s + 1, s // 10) for s in imu_seqs if s % 10 == 0]
    evs += [msg("CAMERA", u) for u in frames]
    evs += [msg("STATE_ESTIMATE", 5000 * s + 2, k) for k, s in enumerate(estimates)]
    return sorted(evs, key=lambda e: e.utime)


# The start: the first estimate at IMU seq 30 after 21 samples received -> the node began at 10.
evs = session(range(0, 100), frames=range(0, 500000, 33333), estimates=range(30, 100))
live = [e.data for e in evs if e.channel == "STATE_ESTIMATE"]
start_seq, inputs, comparable, loss = re_.plan(evs, live, 5000 * 30, 21, "CAMERA")
check(start_seq == 10, "start seq %d, expected 10" % start_seq)
check(inputs[0].channel == "IMU" and re_.seq_of(inputs[0].data) == 10,
      "the replay starts at the node's first IMU sample")
check(all(e.channel in re_.SENSORS + ("CAMERA",) for e in inputs), "estimates are not replayed")
check(loss is None and len(comparable) == len(live), "a complete log compares everything")

# The logger started after the node: not reproducible.
try:
    re_.plan(evs, live, 5000 * 30, 40, "CAMERA")
    check(False, "a start before the log must be refused")
except re_.NotReproducible:
    pass

# An IMU sample the logger lost at seq 80: estimates from its predecessor's stamp on are left out.
gappy = [e for e in evs if not (e.channel == "IMU" and re_.seq_of(e.data) == 80)]
_, _, comparable, loss = re_.plan(gappy, live, 5000 * 30, 21, "CAMERA")
check(loss is not None and loss[0] == 5000 * 79, "IMU gap found at %s" % (loss,))
check(all(re_.utime_of(d) < 5000 * 79 for d in comparable) and len(comparable) == 49,
      "estimates before the gap: %d" % len(comparable))

# A camera frame the logger lost (a hole in the frame train) is a loss too; early: refused.
holed = [e for e in evs if not (e.channel == "CAMERA" and e.utime == 133332)]
try:
    re_.plan(holed, live, 5000 * 30, 21, "CAMERA")
    check(False, "a loss before half the estimates must be refused")
except re_.NotReproducible as e:
    check("CAMERA" in str(e), "names the camera: %s" % e)

# first_difference: identical, one byte changed, one missing.
check(re_.first_difference(live, list(reversed(live))) is None, "order of the replay log is free")
changed = list(live)
changed[7] = changed[7][:-1] + b"\x00" if changed[7][-1:] != b"\x00" else changed[7] + b"\x01"
check(re_.first_difference(live, changed) == 7, "a changed byte at 7")
check(re_.first_difference(live, live[:5] + live[6:]) == 5, "a missing estimate at 5")

if failures:
    print("FAIL:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("PASS")
