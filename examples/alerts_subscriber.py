#!/usr/bin/env python3
"""Receive bearingd's fault alerts in Python, over iceoryx2 (the `iceoryx2` package on PyPI).

A gateway, an HMI or a maintenance script can start from this. It mirrors the daemon's
`#[repr(C)]` alert record (src/sinks/alerts/payload.rs, docs/ALERTS.md) as a ctypes structure whose
`type_name()` is the Rust type name, so iceoryx2 matches the two.

    pip install iceoryx2==0.10.0
    python3 examples/alerts_subscriber.py --root /run/bearingd/iceoryx2        # the service
    python3 examples/alerts_subscriber.py --root ROOT   # `bearingd run` without a config: the
        # root it prints at start ($XDG_RUNTIME_DIR/bearingd-iox-<hash of the data dir>, or
        # /run/bearingd/iox-<hash> without a runtime directory)

It prints the alerts active when it subscribes (the service keeps them in its history; a
cleared one is no longer active), with `"active_at_start": true`, then each alert as it comes
(`false`), one JSON object per line: the lines of `bearingd alerts --json`. A gap in the sequence numbers means this
subscriber fell behind and lost alerts: it says so. `--count N` exits 0 after N alerts,
`--timeout S` exits 1 if they did not come in time.

Run it as the daemon's user (`runuser -u bearingd -- python3 ...`). It trusts only what the
kernel attests (docs/ALERTS.md, "Trust model"): the root, the service's and its wake event's
files must belong to `--expect-uid` (default: this process's user), the service must take one
publisher, and every live process on it must run as that user; else it exits 2 with the
reason. A jump in the sequence numbers that no overflow explains is printed as "untrusted",
not as an alert.
"""

import argparse
import ctypes
import json
import os
import stat
import sys
import time

import iceoryx2 as iox

ALERT_VERSION = 1
STATES = {1: "raised", 2: "escalated", 3: "relaxed", 4: "cleared", 5: "repeated"}
FAULTS = {
    1: "outer_race",
    2: "inner_race",
    3: "ball",
    4: "cage",
    5: "iso_zone",
    6: "unbalance",
    7: "misalignment",
    8: "looseness",
}
SEVERITIES = {0: "ok", 1: "watch", 2: "alarm"}


class Alert(ctypes.Structure):
    """bearingd::Alert, layout version 1: 144 bytes, no padding."""

    _fields_ = [
        ("sequence", ctypes.c_uint64),
        ("run_id", ctypes.c_uint64),
        ("end_sample", ctypes.c_uint64),
        ("wall_time_ns", ctypes.c_uint64),
        ("sample_rate_hz", ctypes.c_double),
        ("fault_frequency_hz", ctypes.c_double),
        ("score", ctypes.c_double),
        ("confidence", ctypes.c_double),
        ("twin_error", ctypes.c_double),
        ("version", ctypes.c_uint32),
        ("state", ctypes.c_uint8),
        ("fault", ctypes.c_uint8),
        ("severity", ctypes.c_uint8),
        ("previous_severity", ctypes.c_uint8),
        ("sensor", ctypes.c_char * 32),
        ("axis", ctypes.c_char * 32),
    ]

    @staticmethod
    def type_name() -> str:
        return "bearingd::Alert"

    def to_dict(self) -> dict:
        twin = self.twin_error
        return {
            "sequence": self.sequence,
            "run_id": self.run_id,
            "sensor": self.sensor.decode("ascii", "replace"),
            "axis": self.axis.decode("ascii", "replace"),
            "fault": FAULTS.get(self.fault, f"unknown({self.fault})"),
            "state": STATES.get(self.state, f"unknown({self.state})"),
            "severity": SEVERITIES.get(self.severity, f"unknown({self.severity})"),
            "previous_severity": SEVERITIES.get(self.previous_severity, "unknown"),
            "confidence": self.confidence,
            "score": self.score,
            # NaN (a detector's alert has no fault frequency) is null, as in `bearingd alerts`.
            "fault_frequency_hz": self.fault_frequency_hz if self.fault_frequency_hz == self.fault_frequency_hz else None,
            "twin_error": twin if twin == twin else None,  # NaN: no twin fit yet
            "end_sample": self.end_sample,
            "sample_time_s": self.end_sample / self.sample_rate_hz if self.sample_rate_hz > 0 else None,
            "wall_time_ns": self.wall_time_ns,
        }


assert ctypes.sizeof(Alert) == 144 and ctypes.alignment(Alert) == 8


class Untrusted(Exception):
    """The root, the service or its publisher is not the expected user's."""


def check_root(root: str, uid: int) -> bool:
    """The root must be a directory (not a link) of `uid`, not writable by group or others.
    False while it does not exist yet."""
    try:
        info = os.lstat(root)
    except FileNotFoundError:
        return False
    if not stat.S_ISDIR(info.st_mode):
        raise Untrusted(f"iceoryx2 root {root} is not a directory (a link or a file)")
    if info.st_uid != uid:
        raise Untrusted(f"iceoryx2 root {root} is owned by uid {info.st_uid}, not uid {uid}: run as the daemon's user (runuser -u bearingd -- ...)")
    if info.st_mode & 0o022:
        raise Untrusted(f"iceoryx2 root {root} is mode {stat.S_IMODE(info.st_mode):04o}: others may have planted services")
    return True


def proc_uid(pid: int):
    """The effective uid of process `pid` (from /proc, not from the node's own records)."""
    try:
        with open(f"/proc/{pid}/status") as status:
            for line in status:
                if line.startswith("Uid:"):
                    return int(line.split()[2])
    except OSError:
        return None
    return None


def verify(args, config, service, wake):
    """The checks of bearingd's own subscriber (src/sinks/alerts/verify.rs), with what the
    Python API offers: it lists no publishers, so every live node on the service must be of
    the expected user."""
    prefix = config.global_cfg.prefix.to_string()
    for what, factory in ((args.service, service), (args.service + "/wake", wake)):
        path = os.path.join(args.root, "services", f"{prefix}{factory.service_hash.as_str}.service")
        try:
            info = os.lstat(path)
        except OSError as error:
            raise Untrusted(f"{what}: its static file {path} cannot be looked at ({error})")
        if not stat.S_ISREG(info.st_mode) or info.st_uid != args.expect_uid:
            raise Untrusted(f"{what} was created by uid {info.st_uid} ({path}), not by uid {args.expect_uid}")
    if service.static_config.max_publishers != 1 or wake.static_config.max_notifiers != 1:
        raise Untrusted(f"{args.service} admits more than one publisher: bearingd did not make it")
    if service.dynamic_config.number_of_publishers > 1:
        raise Untrusted(f"{args.service} has {service.dynamic_config.number_of_publishers} publishers, not one")
    for state in service.nodes:
        if isinstance(state, iox.NodeState.Dead):
            continue
        if not isinstance(state, iox.NodeState.Alive):
            raise Untrusted(f"{args.service}: a node this user cannot look at uses it ({state!r})")
        details = state[0].details
        pid = details.process_id if details is not None else None
        uid = proc_uid(pid) if pid is not None else None
        if uid != args.expect_uid:
            raise Untrusted(f"{args.service}: pid {pid} on it runs as uid {uid}, not uid {args.expect_uid}")


def open_service(args):
    """Opens the daemon's alert service and its wake-up event once they exist and pass the
    owner checks; waits for the daemon (until --timeout)."""
    config = iox.config.default()
    config.global_cfg.root_path = iox.Path.new(args.root)
    if args.prefix:
        config.global_cfg.prefix = iox.FileName.new(args.prefix)
    deadline = time.monotonic() + args.timeout if args.timeout else None
    said = False
    node = None
    while True:
        try:
            if check_root(args.root, args.expect_uid):
                if node is None:
                    node = (
                        iox.NodeBuilder.new()
                        .config(config)
                        .signal_handling_mode(iox.SignalHandlingMode.Disabled)
                        .create(iox.ServiceType.Ipc)
                    )
                service = (
                    node.service_builder(iox.ServiceName.new(args.service))
                    .publish_subscribe(Alert)
                    .open()
                )
                # Opened, never created: the daemon makes it with its one notifier.
                wake = node.service_builder(iox.ServiceName.new(args.service + "/wake")).event().open()
                break
            error = "the root does not exist yet"
        except Untrusted:
            raise
        except Exception as failure:  # the daemon has not created it yet
            error = repr(failure)
        if deadline is not None and time.monotonic() > deadline:
            sys.exit(f"alert service {args.service} under {args.root}: {error}; is bearingd running?")
        if not said:
            print(f"waiting for bearingd ({args.service} under {args.root}: {error})", file=sys.stderr)
            said = True
        time.sleep(0.5)
    verify(args, config, service, wake)
    static = service.static_config
    history = static.history_size
    buffer = static.subscriber_max_buffer_size
    subscriber = service.subscriber_builder().buffer_size(buffer).history_request(min(history, buffer)).create()
    listener = wake.listener_builder().create()
    return node, subscriber, listener, buffer


def judge(batch, last, expect_first, buffer):
    """The sequence rule of src/sinks/alerts/sequence.rs for one drain pass: yields
    ("alert" | "lost" | "new_run" | "untrusted", data) and returns the new `last`."""
    out = []
    for i, alert in enumerate(batch):
        if last is not None and last[0] == alert.run_id:
            expected, new_run = last[1] + 1, False
        elif last is not None:
            expected, new_run = 1, True
        else:
            expected, new_run = (1 if expect_first else None), False
        lost = None
        if expected is not None:
            if alert.sequence < expected:
                continue
            if alert.sequence > expected:
                tail = batch[i : i + buffer]
                overflow = len(tail) >= buffer and all(
                    a.run_id == alert.run_id and a.sequence == alert.sequence + k for k, a in enumerate(tail)
                )
                if not overflow:
                    out.append(("untrusted", {"run_id": alert.run_id, "sequence": alert.sequence, "expected": expected}))
                    continue
                lost = {"run_id": alert.run_id, "first": expected, "last": alert.sequence - 1}
        if new_run:
            out.append(("new_run", {"run_id": alert.run_id}))
        if lost:
            out.append(("lost", lost))
        last = (alert.run_id, alert.sequence)
        expect_first = False
        out.append(("alert", alert))
    return out, last, expect_first


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default="/run/bearingd/iceoryx2", help="the daemon's outputs.iceoryx2_root")
    parser.add_argument("--service", default="bearingd/alerts", help="the daemon's outputs.alerts_service")
    parser.add_argument("--prefix", default=None, help="iceoryx2 file prefix (tests only)")
    parser.add_argument("--expect-uid", type=int, default=os.geteuid(), help="the daemon's uid (default: this user's)")
    parser.add_argument("--count", type=int, default=None, help="exit after this many alerts")
    parser.add_argument("--timeout", type=float, default=None, help="give up after this many seconds")
    args = parser.parse_args()

    try:
        node, subscriber, listener, buffer = open_service(args)
    except Untrusted as refusal:
        print(f"refused: {refusal}", file=sys.stderr)
        return 2
    deadline = time.monotonic() + args.timeout if args.timeout else None
    last = None  # (run_id, sequence) of the newest alert accepted
    expect_first = False
    history_until = time.monotonic() + 0.4  # the daemon hands its history within ~50 ms
    seen_any = False
    received = 0
    # While the history comes: the alert active on each (sensor, axis, fault), as
    # `bearingd alerts` keeps them; printed once the history is in.
    active = {}
    in_history = True
    # An alert of a block completed after we subscribed came live while the history was read:
    # printed as live after the active ones (a quick raise and clear is not folded away).
    subscribed_ns = time.time_ns()
    came_live = []

    def emit(alert, active_at_start):
        """Prints one alert as `bearingd alerts --json` does; True once --count is reached."""
        nonlocal received
        record = alert.to_dict()
        record["type"] = "alert"
        record["active_at_start"] = active_at_start
        record["received_wall_ns"] = time.time_ns()
        print(json.dumps(record), flush=True)
        received += 1
        return args.count is not None and received >= args.count

    while deadline is None or time.monotonic() < deadline:
        # Sleep until the daemon signals an alert (at most 200 ms, so the deadline is kept).
        listener.timed_wait(iox.Duration.from_millis(200))
        batch = []
        while (sample := subscriber.receive()) is not None:
            alert = Alert.from_buffer_copy(sample.payload().contents)
            if alert.version != ALERT_VERSION:
                print(f"alert layout version {alert.version} is not {ALERT_VERSION}: update this script", file=sys.stderr)
                return 2
            batch.append(alert)
        if batch:
            seen_any = True
        elif not seen_any and last is None and time.monotonic() >= history_until:
            expect_first = True  # an empty history: the daemon's next alert is number 1
        verdicts, last, expect_first = judge(batch, last, expect_first, buffer)
        for kind, data in verdicts:
            if kind != "alert":
                print(json.dumps({"type": kind, **data}), flush=True)
            elif in_history and data.wall_time_ns > subscribed_ns:
                came_live.append(data)
            elif in_history:
                key = (bytes(data.sensor), bytes(data.axis), data.fault)
                if STATES.get(data.state) == "cleared":
                    active.pop(key, None)
                else:
                    active[key] = data
            elif emit(data, False):
                return 0
        if in_history and time.monotonic() >= history_until:
            in_history = False
            for key in sorted(active):
                if emit(active[key], True):
                    return 0
            for alert in came_live:
                if emit(alert, False):
                    return 0
    if args.count is not None:
        print(f"{received} of {args.count} alert(s) arrived within {args.timeout} s", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
