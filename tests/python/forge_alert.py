#!/usr/bin/env python3
"""A hostile neighbour of bearingd's alert service, for tests/suite/hostile_alerts.rs (issue 32).

    forge_alert.py --root R --publish --sequence 1000000 --state raised --fault inner_race
        opens the daemon's service and tries to publish one forged alert (sensor "forged");
    forge_alert.py --root R --create [--shape bad] --hold 60
        creates the service first (bearingd's shape, or "bad": two publishers) and holds it.

It prints "ready" once it holds a publisher, and exits 3 when iceoryx2 refuses it (the service
is exclusive), 0 when the forgery went out.
"""

import argparse
import ctypes
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "examples"))
import iceoryx2 as iox  # noqa: E402
from alerts_subscriber import ALERT_VERSION, FAULTS, SEVERITIES, STATES, Alert  # noqa: E402

REFUSED = 3


def code(table, name):
    return next(k for k, v in table.items() if v == name)


def forged(args) -> Alert:
    alert = Alert()
    alert.sequence = args.sequence
    alert.run_id = args.run_id
    alert.end_sample = 1
    alert.sample_rate_hz = 12800.0
    alert.fault_frequency_hz = 160.0
    alert.score = 99.0
    alert.confidence = 1.0
    alert.twin_error = 0.0
    alert.version = ALERT_VERSION
    alert.state = code(STATES, args.state)
    alert.fault = code(FAULTS, args.fault)
    alert.severity = code(SEVERITIES, args.severity)
    alert.previous_severity = 0
    alert.sensor = args.sensor.encode()
    alert.axis = b"radial"
    return alert


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--root", required=True)
    parser.add_argument("--service", default="bearingd/alerts")
    parser.add_argument("--prefix", default=None)
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--publish", action="store_true")
    mode.add_argument("--create", action="store_true")
    parser.add_argument("--shape", choices=["bearingd", "bad"], default="bearingd")
    parser.add_argument("--hold", type=float, default=0.0, help="seconds to keep the publisher")
    parser.add_argument("--sequence", type=int, default=1)
    parser.add_argument("--run-id", type=int, default=1)
    parser.add_argument("--state", default="raised", choices=list(STATES.values()))
    parser.add_argument("--fault", default="inner_race", choices=list(FAULTS.values()))
    parser.add_argument("--severity", default="alarm", choices=list(SEVERITIES.values()))
    parser.add_argument("--sensor", default="forged")
    args = parser.parse_args()

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
    builder = node.service_builder(iox.ServiceName.new(args.service)).publish_subscribe(Alert)
    try:
        if args.create:
            builder = builder.history_size(8).subscriber_max_buffer_size(256).enable_safe_overflow(True)
            builder = builder.max_publishers(2 if args.shape == "bad" else 1)
            service = builder.create()
        else:
            service = builder.open()
        publisher = service.publisher_builder().create()
    except Exception as error:
        print(f"refused: {error!r}", flush=True)
        return REFUSED
    print("ready", flush=True)
    if args.publish:
        sample = publisher.loan_uninit()
        sample = sample.write_payload(forged(args))
        sample.send()
        try:
            wake = node.service_builder(iox.ServiceName.new(args.service + "/wake")).event().open()
            wake.notifier_builder().create().notify()
        except Exception as error:
            print(f"no wake-up: {error!r}", flush=True)
    deadline = time.monotonic() + args.hold
    while time.monotonic() < deadline:
        publisher.update_connections() if hasattr(publisher, "update_connections") else None
        time.sleep(0.05)
    return 0


if __name__ == "__main__":
    sys.exit(main())
