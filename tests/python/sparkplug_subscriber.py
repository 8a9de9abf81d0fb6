#!/usr/bin/env python3
"""A Sparkplug B host for the fleet bridge's tests: subscribes to spBv1.0/# on a real broker
(paho-mqtt, TLS, user name and password), decodes every payload with Python's protobuf package
against proto/sparkplug_b.proto compiled by protoc (independent of bearingd's prost structs),
writes each message as a JSON line, and on end of stdin checks the Sparkplug rules over all of
them and prints a summary as one JSON object.

The rules checked (each break is listed under "violations"):
- NBIRTH: seq 0, a bdSeq metric (UInt64), a `Node Control/Rebirth` metric (Boolean);
- within a session every DBIRTH/DDATA/DDEATH has the seq after the previous message's (mod 256);
- a DDATA comes from a device born in the session and not dead since, and names only metrics
  of that device's DBIRTH, each with the datatype declared there;
- aliases: every metric of an NBIRTH or DBIRTH has a name and an alias, the aliases of a node's
  births are unique within the node (a rebirth starts afresh; a device born again replaces its
  own); a DDATA metric carries an alias and no name, and the alias is one its device's DBIRTH
  of the same session declared. The host names DDATA metrics by those aliases, so the JSON
  lines and the checks below see names;
- an NDEATH carries the bdSeq of the session's NBIRTH.

The session is persistent (clean_session false, QoS 1) and the test broker queues QoS 0 messages
for it, so a broker restart loses nothing on the subscriber's side. MQTT-level duplicates
(the same topic and bytes again, e.g. a redelivery after the subscriber's own reconnect) are
counted, not checked twice.

STATE messages of primary hosts (spBv1.0/STATE/<host>, Sparkplug 3.0 JSON, not protobuf) are
written as lines of type "STATE" with their payload as text, and are not checked.

Usage: sparkplug_subscriber.py --port P --cafile CA --username U --password P --proto FILE
           --out messages.jsonl [--client-id ID] [--rebirth-after N]
Prints `READY` once subscribed. Each stdin line `state HOST retain|once PAYLOAD` publishes PAYLOAD
on spBv1.0/STATE/HOST at QoS 1 (retained or not) and prints `PUBLISHED` once the broker has it;
on end of stdin prints the summary and exits.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time

import paho.mqtt.client as mqtt
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

REBIRTH = "Node Control/Rebirth"
RECORD = "bearingd/Record"
UINT64, DOUBLE, BOOLEAN, STRING = 8, 10, 11, 12
VALUE_FIELDS = {
    "int_value",
    "long_value",
    "float_value",
    "double_value",
    "boolean_value",
    "string_value",
}


def payload_class(proto):
    """The Payload message class from the .proto, compiled by protoc into a descriptor set."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "sparkplug.pb")
        subprocess.run(
            [
                "protoc",
                f"--proto_path={os.path.dirname(os.path.abspath(proto))}",
                f"--descriptor_set_out={out}",
                os.path.basename(proto),
            ],
            check=True,
        )
        with open(out, "rb") as f:
            files = descriptor_pb2.FileDescriptorSet.FromString(f.read())
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    descriptor = pool.FindMessageTypeByName("org.eclipse.tahu.protobuf.Payload")
    return message_factory.GetMessageClass(descriptor)


def metric_value(m):
    if m.is_null:
        return None
    which = m.WhichOneof("value")
    return getattr(m, which) if which in VALUE_FIELDS else None


def decode(payload_cls, topic, raw, received_ms):
    parts = topic.split("/")
    payload = payload_cls.FromString(raw)
    metrics = []
    for m in payload.metrics:
        metrics.append(
            {
                "name": m.name if m.HasField("name") else None,
                "alias": m.alias if m.HasField("alias") else None,
                "value": metric_value(m),
                "datatype": m.datatype,
                "timestamp": m.timestamp,
                "historical": m.is_historical,
                "null": m.is_null,
            }
        )
    return {
        "topic": topic,
        "group": parts[1] if len(parts) > 1 else None,
        "type": parts[2] if len(parts) > 2 else None,
        "node": parts[3] if len(parts) > 3 else None,
        "device": parts[4] if len(parts) > 4 else None,
        "seq": payload.seq if payload.HasField("seq") else None,
        "timestamp": payload.timestamp if payload.HasField("timestamp") else None,
        "received_ms": received_ms,
        "bytes": len(raw),
        "metrics": metrics,  # a list until Checker.take names them (by alias in DDATA)
    }


class Checker:
    """The Sparkplug rules over the messages of every node, in arrival order."""

    def __init__(self):
        self.violations = []
        self.nodes = {}  # node -> session state
        self.births = []  # (node, bdSeq) in order
        self.deaths = []  # (node, bdSeq, matched)
        self.device_deaths = []
        self.records = []  # one per DDATA carrying bearingd/Record
        # What the alias checks saw: births whose metrics all had aliases, DDATA metrics named
        # by a declared alias.
        self.aliases = {"births": 0, "declared": 0, "ddata_metrics": 0}

    def violation(self, msg, text):
        self.violations.append(f"{msg['topic']} seq {msg['seq']}: {text}")

    def declare(self, msg, state):
        """A birth's aliases into the node's map (alias -> (device, name))."""
        device = msg["device"]
        aliases = state["aliases"]
        for alias in [a for a, (d, _) in aliases.items() if d == device]:
            del aliases[alias]  # a device born again declares its own anew
        complete = True
        for m in msg["metrics"]:
            if m["name"] is None:
                self.violation(msg, f"a birth metric without a name (alias {m['alias']})")
                complete = False
            elif m["alias"] is None:
                self.violation(msg, f"birth metric {m['name']!r} without an alias")
                complete = False
            elif m["alias"] in aliases:
                owner = aliases[m["alias"]]
                self.violation(
                    msg, f"alias {m['alias']} of {m['name']!r} already declared for {owner}"
                )
                complete = False
            else:
                aliases[m["alias"]] = (device, m["name"])
                self.aliases["declared"] += 1
        self.aliases["births"] += complete

    def name_metrics(self, msg, state):
        """The message's metric list as a dict by name; DDATA's names from their aliases."""
        named = {}
        for m in msg["metrics"]:
            name = m["name"]
            if msg["type"] == "DDATA":
                if name is not None:
                    self.violation(msg, f"DDATA metric {name!r} carries its name")
                if m["alias"] is None:
                    self.violation(msg, f"DDATA metric {name!r} without an alias")
                elif state is not None:
                    device, declared = state["aliases"].get(m["alias"], (None, None))
                    if declared is None or device != msg["device"]:
                        self.violation(
                            msg,
                            f"DDATA alias {m['alias']} is not declared by the device's DBIRTH",
                        )
                    elif name is None:
                        name = declared
                        self.aliases["ddata_metrics"] += 1
            if name is None:
                name = f"#{m['alias']}"
            named[name] = m
        msg["metrics"] = named

    def take(self, msg):
        kind, node = msg["type"], (msg["group"], msg["node"])
        state = self.nodes.get(node)
        if kind in ("NBIRTH", "DBIRTH"):
            if kind == "NBIRTH":
                state = {"bd_seq": None, "seq": 0, "devices": {}, "aliases": {}}
            if state is not None:
                self.declare(msg, state)
        self.name_metrics(msg, state)
        if kind == "NBIRTH":
            bd = msg["metrics"].get("bdSeq")
            if msg["seq"] != 0:
                self.violation(msg, "NBIRTH seq is not 0")
            if bd is None or bd["datatype"] != UINT64:
                self.violation(msg, "NBIRTH without a UInt64 bdSeq metric")
            rebirth = msg["metrics"].get(REBIRTH)
            if rebirth is None or rebirth["datatype"] != BOOLEAN:
                self.violation(msg, f"NBIRTH without a Boolean {REBIRTH!r} metric")
            bd_seq = bd["value"] if bd else None
            self.births.append([msg["node"], bd_seq])
            state["bd_seq"] = bd_seq
            self.nodes[node] = state
            return
        if kind == "NDEATH":
            bd = msg["metrics"].get("bdSeq")
            bd_seq = bd["value"] if bd else None
            matched = state is not None and state["bd_seq"] == bd_seq
            self.deaths.append([msg["node"], bd_seq, matched])
            if bd is None:
                self.violation(msg, "NDEATH without a bdSeq metric")
            # A Will of an earlier session may arrive after a new birth (the broker notices a
            # dead link late): that is not this session's death.
            if matched:
                self.nodes.pop(node, None)
            return
        if kind == "NCMD" or kind == "DCMD":
            return
        if state is None:
            self.violation(msg, f"{kind} before any NBIRTH of its node")
            return
        expected = (state["seq"] + 1) % 256
        if msg["seq"] != expected:
            self.violation(msg, f"seq {msg['seq']}, expected {expected}")
        state["seq"] = msg["seq"] if msg["seq"] is not None else state["seq"]
        device = msg["device"]
        if kind == "DBIRTH":
            state["devices"][device] = {
                name: m["datatype"] for name, m in msg["metrics"].items()
            }
        elif kind == "DDEATH":
            if device not in state["devices"]:
                self.violation(msg, "DDEATH of a device not born")
            state["devices"].pop(device, None)
            self.device_deaths.append([msg["node"], device])
        elif kind == "DDATA":
            declared = state["devices"].get(device)
            if declared is None:
                self.violation(msg, "DDATA of a device not born in this session")
                declared = {}
            for name, m in msg["metrics"].items():
                if declared and name not in declared:
                    self.violation(msg, f"metric {name!r} not in the device's DBIRTH")
                elif declared and declared[name] != m["datatype"]:
                    self.violation(
                        msg, f"metric {name!r} datatype {m['datatype']} != DBIRTH's"
                    )
            record = msg["metrics"].get(RECORD)
            if record is not None:
                historical = any(
                    m["historical"] for n, m in msg["metrics"].items() if n != RECORD
                )
                self.records.append(
                    {
                        "number": record["value"],
                        "device": device,
                        "timestamp": msg["timestamp"],
                        "received_ms": msg["received_ms"],
                        "historical": historical,
                        "bd_seq": state["bd_seq"],
                        "seq": msg["seq"],
                        "metrics": sorted(msg["metrics"]),
                    }
                )

    def summary(self, counts, duplicates, rebirth_sent):
        numbers = [r["number"] for r in self.records]
        unique = sorted(set(numbers))
        missing = []
        for a, b in zip(unique, unique[1:]):
            if b != a + 1:
                missing.append([a + 1, b - 1])
        first_seen = {}
        resent = []
        for r in self.records:
            if r["number"] in first_seen:
                resent.append(r["number"])
            else:
                first_seen[r["number"]] = r
        # First arrivals in record order must have non-decreasing timestamps per device.
        out_of_order = []
        last = {}
        for n in unique:
            r = first_seen[n]
            if r["device"] in last and r["timestamp"] < last[r["device"]]:
                out_of_order.append(n)
            last[r["device"]] = r["timestamp"]
        return {
            "counts": counts,
            "mqtt_duplicates": duplicates,
            "violations": self.violations,
            "births": self.births,
            "deaths": self.deaths,
            "device_deaths": self.device_deaths,
            "rebirth_sent": rebirth_sent,
            "aliases": self.aliases,
            "records": {
                "count": len(unique),
                "first": unique[0] if unique else None,
                "last": unique[-1] if unique else None,
                "missing": missing,
                "resent": resent,
                "out_of_order": out_of_order,
                "historical": sum(1 for r in first_seen.values() if r["historical"]),
            },
            "record_list": [first_seen[n] for n in unique],
        }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--cafile", required=True)
    ap.add_argument("--username", required=True)
    ap.add_argument("--password", required=True)
    ap.add_argument("--proto", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--client-id", default="sparkplug-test-host")
    ap.add_argument(
        "--rebirth-after",
        type=int,
        default=0,
        help="send an NCMD rebirth to the first node after this many DDATA (0: never)",
    )
    args = ap.parse_args()

    payload_cls = payload_class(args.proto)
    checker = Checker()
    lock = threading.Lock()
    out = open(args.out, "w", encoding="utf-8")
    seen = set()
    counts = {}
    state = {"duplicates": 0, "rebirth_sent": False, "ddata": 0}
    subscribed = threading.Event()

    def on_connect(client, _userdata, _flags, reason_code, _properties):
        if reason_code.is_failure:
            print(f"subscriber: connect refused: {reason_code}", file=sys.stderr, flush=True)
            return
        client.subscribe("spBv1.0/#", qos=1)

    def on_subscribe(_client, _userdata, _mid, _reason_codes, _properties):
        subscribed.set()

    def on_message(client, _userdata, message):
        received_ms = int(time.time() * 1000)
        key = (message.topic, bytes(message.payload))
        with lock:
            if key in seen:
                state["duplicates"] += 1
                return
            seen.add(key)
            if message.topic.startswith("spBv1.0/STATE/"):
                counts["STATE"] = counts.get("STATE", 0) + 1
                state_line = {
                    "topic": message.topic,
                    "type": "STATE",
                    "host": message.topic.split("/", 2)[2],
                    "payload": bytes(message.payload).decode("utf-8", "replace"),
                    "received_ms": received_ms,
                }
                out.write(json.dumps(state_line) + "\n")
                out.flush()
                return
            try:
                msg = decode(payload_cls, message.topic, message.payload, received_ms)
            except Exception as e:  # a payload our .proto cannot read is a finding
                checker.violations.append(f"{message.topic}: undecodable payload: {e}")
                return
            counts[msg["type"]] = counts.get(msg["type"], 0) + 1
            checker.take(msg)
            out.write(json.dumps(msg) + "\n")
            out.flush()
            if msg["type"] == "DDATA":
                state["ddata"] += 1
            if (
                args.rebirth_after
                and not state["rebirth_sent"]
                and state["ddata"] >= args.rebirth_after
            ):
                command = payload_cls()
                command.timestamp = received_ms
                m = command.metrics.add()
                m.name = REBIRTH
                m.timestamp = received_ms
                m.datatype = BOOLEAN
                m.boolean_value = True
                topic = f"spBv1.0/{msg['group']}/NCMD/{msg['node']}"
                client.publish(topic, command.SerializeToString(), qos=1)
                state["rebirth_sent"] = True

    client = mqtt.Client(
        mqtt.CallbackAPIVersion.VERSION2,
        client_id=args.client_id,
        clean_session=False,
        protocol=mqtt.MQTTv311,
    )
    client.tls_set(ca_certs=args.cafile)
    client.username_pw_set(args.username, args.password)
    client.reconnect_delay_set(min_delay=0.2, max_delay=1)
    client.on_connect = on_connect
    client.on_subscribe = on_subscribe
    client.on_message = on_message
    client.connect_async(args.host, args.port, keepalive=10)
    client.loop_start()
    if not subscribed.wait(30):
        print("subscriber: not subscribed within 30 s", file=sys.stderr, flush=True)
        sys.exit(2)
    print("READY", flush=True)
    for line in sys.stdin:
        words = line.rstrip("\n").split(" ", 3)
        if len(words) == 4 and words[0] == "state":
            _, host, retain, payload = words
            info = client.publish(
                f"spBv1.0/STATE/{host}",
                payload.encode("utf-8"),
                qos=1,
                retain=retain == "retain",
            )
            info.wait_for_publish(15)
            print("PUBLISHED" if info.is_published() else "NOT PUBLISHED", flush=True)
        elif line.strip():
            print(f"subscriber: unknown command {line!r}", file=sys.stderr, flush=True)
    time.sleep(0.3)  # what is on its way
    client.loop_stop()
    client.disconnect()
    with lock:
        summary = checker.summary(counts, state["duplicates"], state["rebirth_sent"])
    print(json.dumps(summary), flush=True)


if __name__ == "__main__":
    main()
