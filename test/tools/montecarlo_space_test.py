"""scripts/montecarlo stops before a flight when the disk where the session logs go is short of
room (regression: a 120-flight campaign over LCM filled the disk, the last flights had no log and
the campaign then lost its own results.csv). No flight is flown: the threshold is set past any
disk's free space.
Usage: montecarlo_space_test.py SCRIPTS_DIR OUT_DIR"""
import io
import os
import sys
from contextlib import redirect_stderr, redirect_stdout

import script_module

scripts, out = sys.argv[1], sys.argv[2]
mc = script_module.load(scripts, "montecarlo")

flown = []
mc.run_one = lambda *a: flown.append(a) or {}
mc.MIN_FREE_BYTES = 1 << 62
sys.argv = ["montecarlo", "--runs", "2", "--scenarios", "landing_a", "--out", out]
err = io.StringIO()
with redirect_stdout(io.StringIO()), redirect_stderr(err):
    rc = mc.main()
failures = []
if rc != 1:
    failures.append("exit %s, expected 1" % rc)
if flown:
    failures.append("%d flights flown with no room for their logs" % len(flown))
if "stopping before landing_a seed 1" not in err.getvalue():
    failures.append("no message naming the flight it stopped before: %r" % err.getvalue())
if failures:
    print("\n".join(failures))
    sys.exit(1)
print("ok")
