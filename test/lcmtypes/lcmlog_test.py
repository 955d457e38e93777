"""Python side of the log tests: scripts/lcmlog.py reads a log written by LCM's C++ writer and
decodes every event with the lcm-gen Python types. Usage: lcmlog_test.py LOG SCRIPTS_DIR"""
import sys

log, scripts = sys.argv[1], sys.argv[2]
sys.path.insert(0, scripts)
import lcmlog  # noqa: E402

events = list(lcmlog.read_events(log))
assert len(events) == 14, len(events)
decoded = [lcmlog.decode(ev) for ev in events]
assert all(m is not None for m in decoded), [ev.channel for ev, m in zip(events, decoded) if m is None]
poses = [m for ev, m in zip(events, decoded) if ev.channel == "MOCAP_POSE"]
assert len(poses) == 10
assert abs(poses[3].pos[0] - 0.3) < 1e-12 and poses[3].seq == 3, (poses[3].pos, poses[3].seq)
image = [m for ev, m in zip(events, decoded) if ev.channel == "CAMERA"][0]
assert (image.width, image.height, len(image.data)) == (640, 480, 640 * 480)
assert image.metadata[0].key == "seq"
target = [m for ev, m in zip(events, decoded) if ev.channel == "VISION_TARGET"][0]
assert target.found and target.p_W_target[0] == 1.25
status = [m for ev, m in zip(events, decoded) if ev.channel == "AUTONOMY_STATUS"][0]
assert status.phase_name == "REFINEMENT"
assert len(list(lcmlog.read_events(log, "MOCAP_.*"))) == 10
summary = lcmlog.summary(log)
assert summary["MOCAP_POSE"]["type"] == "pose_t" and summary["MOCAP_POSE"]["n"] == 10

# A log cut short mid-event (a logger killed while writing) yields the complete events only.
with open(log, "rb") as f:
    data = f.read()
cut = log + ".cut"
with open(cut, "wb") as f:
    f.write(data[:-5])
assert len(list(lcmlog.read_events(cut))) == 13
# Corruption in the middle is reported with its offset.
first_len = 28 + len(events[0].channel) + len(events[0].data)  # header + channel + payload
with open(cut, "wb") as f:
    f.write(data[:first_len] + b"\x00" * 4 + data[first_len + 4:])
try:
    list(lcmlog.read_events(cut))
    raise AssertionError("corruption not detected")
except lcmlog.LogFormatError as e:
    assert ("byte %d" % first_len) in str(e), str(e)
print("1 passed, 0 failed")
