#!/usr/bin/env python3
"""Reads LCM log files (.lcmlog) and decodes alight messages, without the LCM Python module.

Debian ships no Python binding for LCM, but the Python code lcm-gen writes needs only `struct`,
so analysis scripts can read session logs with this module:

    import lcmlog
    for ev in lcmlog.read_events("logs/20261122-101500-landing/session.lcmlog"):
        msg = lcmlog.decode(ev)          # an alight.*_t instance, or None if the type is unknown
        print(ev.utime, ev.channel, type(msg).__name__)

Run as a script it prints a summary: channels, message counts, types and rates.
The generated types are found in build/lcmtypes/python (or $ALIGHT_LCMTYPES_PYTHON).
"""
import argparse
import collections
import os
import re
import struct
import sys
import time

SYNC = 0xEDA1DA01
_HEADER = struct.Struct(">IqqII")  # sync, event number, utime, channel length, data length

Event = collections.namedtuple("Event", "eventnum utime channel data")

# The origin trailer every alight publisher appends (common/bus_auth.hpp): source id, counter,
# key id, flags, tag, magic; lcm-gen's decoders ignore it.
TRAILER_BYTES = 38
TRAILER_MAGIC = b"ALB1"
Trailer = collections.namedtuple("Trailer", "source counter key_id flags tag")


def payload(data):
    """The message without its origin trailer (the bytes lcm-gen encoded)."""
    if len(data) >= TRAILER_BYTES and data[-4:] == TRAILER_MAGIC:
        return data[:-TRAILER_BYTES]
    return data


def trailer(data):
    """The message's origin trailer (publisher id, counter, key id, flags, tag), or None."""
    if len(data) < TRAILER_BYTES or data[-4:] != TRAILER_MAGIC:
        return None
    t = data[-TRAILER_BYTES:]
    source, counter, key_id, flags = struct.unpack(">QQBB", t[:18])
    return Trailer(source, counter, key_id, flags, t[18:34])


class LogFormatError(Exception):
    pass


def read_events(path, channel_regex=None):
    """Yields every Event of the log in file order. A log cut short (a crashed logger) ends at the
    last complete event; a corrupted event in the middle raises LogFormatError naming its offset."""
    pattern = re.compile(channel_regex) if channel_regex else None
    with open(path, "rb") as f:
        while True:
            offset = f.tell()
            header = f.read(_HEADER.size)
            if len(header) < _HEADER.size:
                return
            sync, eventnum, utime, chan_len, data_len = _HEADER.unpack(header)
            if sync != SYNC:
                raise LogFormatError("%s: bad sync word 0x%08x at byte %d" % (path, sync, offset))
            channel = f.read(chan_len)
            data = f.read(data_len)
            if len(channel) < chan_len or len(data) < data_len:
                return
            channel = channel.decode("utf-8", "replace")
            if pattern is None or pattern.fullmatch(channel):
                yield Event(eventnum, utime, channel, data)


def wait_started(procs, out_path, marker, log_path, timeout_s):
    """Waits until a node's output (out_path) holds `marker`, the line it logs once subscribed,
    and lcm-logger has created log_path (it does as it subscribes): what is played before both
    listen is lost, and a loaded machine starts them late. False where a process in `procs`
    exits or timeout_s passes first."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if any(p.poll() is not None for p in procs):
            return False
        with open(out_path, errors="replace") as f:
            up = marker in f.read()
        if up and os.path.exists(log_path):
            return True
        time.sleep(0.05)
    return False


def wait_logged(path, n, quiet_s, timeout_s):
    """Waits until the log being written at `path` holds n events, or none more come for quiet_s
    (those it lacks are lost; the caller's comparison says which): the last messages through a
    node and a logger arrive late on a loaded machine, not within a fixed time."""
    last, since = -1, time.monotonic()
    deadline = since + timeout_s
    while time.monotonic() < deadline:
        got = sum(1 for _ in read_events(path)) if os.path.exists(path) else 0
        if got >= n:
            return
        if got != last:
            last, since = got, time.monotonic()
        elif time.monotonic() - since > quiet_s:
            return
        time.sleep(0.1)


def write_events(path, events):
    """Writes Events (their channel, data and utime; renumbered from 0) as an LCM log that
    lcm-logplayer plays; returns how many."""
    n = 0
    with open(path, "wb") as f:
        for ev in events:
            channel = ev.channel.encode()
            f.write(_HEADER.pack(SYNC, n, ev.utime, len(channel), len(ev.data)))
            f.write(channel)
            f.write(ev.data)
            n += 1
    return n


def _types_dir():
    env = os.environ.get("ALIGHT_LCMTYPES_PYTHON")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.join(here, "..", "build", "lcmtypes", "python")


_BY_FINGERPRINT = None


def types_by_fingerprint():
    """Maps the 8-byte packed fingerprint of every alight type to its class."""
    global _BY_FINGERPRINT
    if _BY_FINGERPRINT is None:
        path = os.path.abspath(_types_dir())
        if not os.path.isdir(os.path.join(path, "alight")):
            raise RuntimeError("generated Python types not found in %s (build first, or set "
                               "ALIGHT_LCMTYPES_PYTHON)" % path)
        if path not in sys.path:
            sys.path.insert(0, path)
        import alight  # noqa: E402  (generated by lcm-gen at build time)
        _BY_FINGERPRINT = {}
        for name in dir(alight):
            cls = getattr(alight, name)
            if isinstance(cls, type) and hasattr(cls, "_get_packed_fingerprint"):
                _BY_FINGERPRINT[cls._get_packed_fingerprint()] = cls
    return _BY_FINGERPRINT


def decode(event):
    """Decodes an event's payload with the alight type whose fingerprint it carries; None for an
    unknown type or bytes that do not decode."""
    cls = types_by_fingerprint().get(event.data[:8])
    if cls is None:
        return None
    try:
        return cls.decode(payload(event.data))
    except Exception:  # noqa: BLE001 - a malformed message (garbage in a log) decodes to nothing
        return None


def summary(path, channel_regex=None):
    stats = collections.OrderedDict()
    for ev in read_events(path, channel_regex):
        s = stats.setdefault(ev.channel, {"n": 0, "first": ev.utime, "last": ev.utime, "type": None,
                                          "bytes": 0})
        s["n"] += 1
        s["last"] = ev.utime
        s["bytes"] += len(ev.data)
        if s["type"] is None:
            cls = types_by_fingerprint().get(ev.data[:8])
            s["type"] = cls.__name__ if cls else "unknown"
    return stats


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("--channel", help="regular expression of channels to include")
    args = ap.parse_args()
    stats = summary(args.log, args.channel)
    print("%-20s %-22s %8s %9s %10s" % ("channel", "type", "count", "rate_hz", "kbytes"))
    for chan, s in stats.items():
        span = (s["last"] - s["first"]) * 1e-6
        rate = (s["n"] - 1) / span if span > 0 else 0.0
        print("%-20s %-22s %8d %9.1f %10.1f" % (chan, s["type"], s["n"], rate, s["bytes"] / 1024.0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
