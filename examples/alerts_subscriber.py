#!/usr/bin/env python3
"""Receive bearingd's fault alerts in Python, over iceoryx2 (the `iceoryx2` package on PyPI).

A gateway, an HMI or a maintenance script can start from this. It mirrors the daemon's
`#[repr(C)]` alert record (src/sinks/alerts/payload.rs, docs/ALERTS.md) as a ctypes structure whose
`type_name()` is the Rust type name, so iceoryx2 matches the two.

    pip install iceoryx2==0.10.0
    python3 examples/alerts_subscriber.py --root /run/bearingd/iceoryx2        # the service
    python3 examples/alerts_subscriber.py --root $XDG_RUNTIME_DIR/bearingd-iox-...  # `bearingd run`
                                        # without a config: the root it prints at start

It prints the alerts active when it subscribes (the service keeps them in its history), then
each alert as it comes, one JSON object per line. A gap in the sequence numbers means this
subscriber fell behind and lost alerts: it says so. `--count N` exits 0 after N alerts,
`--timeout S` exits 1 if they did not come in time.
"""

import argparse
import ctypes
import json
import sys
import time

import iceoryx2 as iox

ALERT_VERSION = 1
STATES = {1: "raised", 2: "escalated", 3: "relaxed", 4: "cleared", 5: "repeated"}
FAULTS = {1: "outer_race", 2: "inner_race", 3: "ball", 4: "cage", 5: "iso_zone"}
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
            "fault_frequency_hz": self.fault_frequency_hz,
            "twin_error": twin if twin == twin else None,  # NaN: no twin fit yet
            "end_sample": self.end_sample,
            "sample_time_s": self.end_sample / self.sample_rate_hz if self.sample_rate_hz > 0 else None,
            "wall_time_ns": self.wall_time_ns,
        }


assert ctypes.sizeof(Alert) == 144 and ctypes.alignment(Alert) == 8


def open_service(args):
    """Opens the daemon's alert service and its wake-up event; waits for the daemon."""
    config = iox.config.default()
    config.global_cfg.root_path = iox.Path.new(args.root)
    if args.prefix:
        config.global_cfg.prefix = iox.FileName.new(args.prefix)
    node = (
        iox.NodeBuilder.new()
        .config(config)
        .signal_handling_mode(iox.SignalHandlingMode.Disabled)
        .create(iox.ServiceType.Ipc)
    )
    deadline = time.monotonic() + args.timeout if args.timeout else None
    said = False
    while True:
        try:
            service = (
                node.service_builder(iox.ServiceName.new(args.service))
                .publish_subscribe(Alert)
                .open()
            )
            break
        except Exception as error:  # the daemon has not created it yet
            if deadline is not None and time.monotonic() > deadline:
                sys.exit(f"alert service {args.service} under {args.root}: {error!r}; is bearingd running?")
            if not said:
                print(f"waiting for bearingd ({args.service} under {args.root}: {error!r})", file=sys.stderr)
                said = True
            time.sleep(0.5)
    static = service.static_config
    history = static.history_size
    buffer = static.subscriber_max_buffer_size
    subscriber = service.subscriber_builder().buffer_size(buffer).history_request(min(history, buffer)).create()
    wake = node.service_builder(iox.ServiceName.new(args.service + "/wake")).event().open_or_create()
    listener = wake.listener_builder().create()
    return node, subscriber, listener


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default="/run/bearingd/iceoryx2", help="the daemon's outputs.iceoryx2_root")
    parser.add_argument("--service", default="bearingd/alerts", help="the daemon's outputs.alerts_service")
    parser.add_argument("--prefix", default=None, help="iceoryx2 file prefix (tests only)")
    parser.add_argument("--count", type=int, default=None, help="exit after this many alerts")
    parser.add_argument("--timeout", type=float, default=None, help="give up after this many seconds")
    args = parser.parse_args()

    node, subscriber, listener = open_service(args)
    deadline = time.monotonic() + args.timeout if args.timeout else None
    last = None  # (run_id, sequence) of the newest alert seen
    received = 0
    while deadline is None or time.monotonic() < deadline:
        # Sleep until the daemon signals an alert (at most 200 ms, so the deadline is kept).
        listener.timed_wait(iox.Duration.from_millis(200))
        while (sample := subscriber.receive()) is not None:
            alert = sample.payload().contents
            if alert.version != ALERT_VERSION:
                print(f"alert layout version {alert.version} is not {ALERT_VERSION}: update this script", file=sys.stderr)
                return 2
            if last is not None and last[0] == alert.run_id:
                if alert.sequence <= last[1]:
                    continue
                if alert.sequence > last[1] + 1:
                    print(json.dumps({"type": "lost", "first": last[1] + 1, "last": alert.sequence - 1}), flush=True)
            elif last is not None:
                print(json.dumps({"type": "new_run", "run_id": alert.run_id}), flush=True)
            last = (alert.run_id, alert.sequence)
            record = alert.to_dict()
            record["type"] = "alert"
            record["received_wall_ns"] = time.time_ns()
            print(json.dumps(record), flush=True)
            received += 1
            if args.count is not None and received >= args.count:
                return 0
    if args.count is not None:
        print(f"{received} of {args.count} alert(s) arrived within {args.timeout} s", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
