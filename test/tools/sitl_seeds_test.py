"""scripts/sitl --runs N flies seeds N0 .. N0 + N - 1 (regression: each flight set args.seed to
its own seed and the next was counted from it, so --runs 6 --seed 10827 flew 10827, 10828, 10830,
10833, 10837, 10842). No flight is flown: run_flight is replaced by a recorder that, like the real
one, sets args.seed. And the batch flies a copy of alight's executables made when it starts
(regression: a rebuild during a batch of flights swapped processes under a flight, whose old and
new processes no longer decoded each other's setpoints).
Usage: sitl_seeds_test.py SCRIPTS_DIR OUT_DIR"""
import io
import os
import sys
from contextlib import redirect_stderr, redirect_stdout

import script_module

scripts, out = sys.argv[1], sys.argv[2]
sitl = script_module.load(scripts, "sitl")

os.makedirs(os.path.join(out, "bin"), exist_ok=True)
for name in ["alight-launch", "alight-sim", "alight-mavlink", "alight-outer-loop", "alight-vision",
             "alight-autonomy", "alight-monitor", "alight-score"]:
    open(os.path.join(out, "bin", name), "w").close()
sitl.BIN = os.path.join(out, "bin")
sitl.find_or_build_sitl = lambda args: "/nonexistent/px4"
sitl.summarise = lambda results, path: None
flown = []


def fake_flight(args, seed, out_root):
    args.seed = seed
    flown.append(seed)
    return {"score": {"success": True}}


sitl.run_flight = fake_flight
sys.argv = ["sitl", "px4", "landing", "--runs", "6", "--seed", "10827", "--autopilot-dir", out,
            "--out", os.path.join(out, "runs")]
with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
    rc = sitl.main()
failures = []
if rc != 0:
    failures.append("exit %s, expected 0" % rc)
if flown != list(range(10827, 10833)):
    failures.append("flew seeds %s, expected 10827..10832" % flown)
snap = os.path.join(out, "runs", "bin")
if os.path.realpath(sitl.BIN) != os.path.realpath(snap):
    failures.append("flew from %s, expected the batch's copy %s" % (sitl.BIN, snap))
with open(os.path.join(out, "bin", "alight-vision"), "w") as f:
    f.write("rebuilt")  # a rebuild after the batch started
copied = os.path.join(snap, "alight-vision")
if not os.path.exists(copied) or os.path.getsize(copied) != 0:
    failures.append("the batch's alight-vision is not the copy made at its start")
if failures:
    print("\n".join(failures))
    sys.exit(1)
print("ok")
