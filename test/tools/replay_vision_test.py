"""scripts/replay-vision's bookkeeping without a flight or a network: which frames the live node
processed (from its targets' seq numbers), where the log lost poses, and which differences those
losses explain (regression: a loaded lcm-logger lost the MOCAP_POSE next to a frame; the live
node had interpolated across it, the replay could not, and the replay test failed).
Usage: replay_vision_test.py SCRIPTS_DIR"""
import os
import struct
import sys

import script_module

scripts = sys.argv[1]
sys.path.insert(0, scripts)
rv = script_module.load(scripts, "replay-vision")

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)


def target(utime, ref, seq, tail=b"\x01\x00"):
    """A VISION_TARGET payload as far as replay-vision reads it: fingerprint, utime, ref, seq."""
    return b"F" * 8 + struct.pack(">qqq", utime, ref, seq) + tail


# frames_processed: a target lost by the logger between two seq numbers is a processed frame.
live = [target(100, 0, 1), target(300, 0, 3)]
frames, problems = rv.frames_processed(live, {100, 200, 300, 400})
check(frames == {100, 200, 300} and not problems, "a target the log lost: %s %s" % (frames, problems))
frames, problems = rv.frames_processed(live, {100, 300})
check(problems, "a processed frame the log lost must make it not reproducible")
# Frames the node skipped (too old on a loaded machine, or never received) between targets of
# consecutive seq numbers: not replayed, and the replay still reproducible.
skipped = [target(100, 0, 1), target(400, 0, 2)]
frames, problems = rv.frames_processed(skipped, {100, 200, 300, 400})
check(frames == {100, 400} and not problems, "frames the node skipped: %s %s" % (frames, problems))
# Some of them processed without a logged target, some skipped: which, the log cannot say.
frames, problems = rv.frames_processed([target(100, 0, 1), target(400, 0, 3)], {100, 200, 300, 400})
check(problems, "one of two frames processed, the other skipped, must make it not reproducible")

# pose_gaps: only missing seq numbers make a gap, whatever the order of the log.
gaps = rv.pose_gaps([(3, 30), (1, 10), (2, 20), (5, 50), (6, 60)])
check(gaps == [(30, 50)], "pose gaps %s" % gaps)

# compare: identical; a difference away from a gap; a difference explained by a gap (frame or
# reference frame inside it); a missing target.
a = [target(10, 0, 1), target(40, 10, 2), target(70, 40, 3)]
verdict, lines = rv.compare(a, list(a), gaps)
check(verdict == rv.IDENTICAL and "identical: 3" in lines[-1], "identical: %s" % lines)
b = [a[0], target(40, 10, 2, b"\x01\x01"), a[2]]
verdict, lines = rv.compare(a, b, gaps)
check(verdict == rv.IDENTICAL and "but 1 targets" in lines[-1], "frame in a gap is explained: %s" % lines)
c = [a[0], a[1], target(70, 40, 3, b"\x01\x01")]
verdict, lines = rv.compare(a, c, gaps)
check(verdict == rv.IDENTICAL, "reference frame in a gap is explained: %s" % lines)
d = [target(10, 0, 1, b"\x01\x01"), a[1], a[2]]
verdict, lines = rv.compare(a, d, gaps)
check(verdict == rv.DIFFERS and "first difference at target 0" in lines[0], "difference outside gaps: %s" % lines)
verdict, lines = rv.compare(a, b, [])
check(verdict == rv.DIFFERS, "without the gap the same difference fails")
verdict, lines = rv.compare(a, [a[0], a[2]], gaps)
check(verdict == rv.LOST and "no target for frame 40" in lines[0], "missing target: %s" % lines)
verdict, lines = rv.compare(a, [a[0], a[2], a[1]], gaps)
check(verdict == rv.DIFFERS, "out of order")

for f in failures:
    print("FAIL: " + f)
print("%d checks failed" % len(failures) if failures else "ok")
sys.exit(1 if failures else 0)
