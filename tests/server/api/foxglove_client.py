"""A Foxglove WebSocket protocol client, written from the protocol's specification alone.

It imports nothing of xabsl-studio: the tests run it as a separate process against a real
studio, so what it checks is the wire, as Foxglove or Lichtblick would meet it (ws-protocol
``docs/spec.md``: text messages are JSON objects with an ``op``; binary messages start with a
one-byte opcode, integers little-endian; server opcodes 1 message data, 2 time, 3 service call
response, 5 playback state; client opcodes 2 service call request, 3 playback control request).

It connects offering one subprotocol, reads ``serverInfo`` and the channels advertised,
subscribes to the channels whose topic starts with one of ``--topic`` (all without), validates
every message payload against the JSON Schema its channel advertised (``jsonschema``, draft
2020-12), optionally calls a service and drives playback, and prints one JSON report to stdout.

    python foxglove_client.py ws://127.0.0.1:8000/foxglove --subprotocol foxglove.sdk.v1 \
        [--token T] [--topic /xabsl/] [--wait /xabsl/agents/] [--messages 20] [--seek-ns NS] \
        [--call NAME JSON]
"""

from __future__ import annotations

import argparse
import json
import struct
import sys
import time
from typing import Any

from jsonschema import Draft202012Validator
from websockets.sync.client import ClientConnection, connect

SECONDS = 30.0


class Viewer:
    """What the client learned: server info, channels, received messages, statuses."""

    def __init__(self, ws: ClientConnection, prefixes: list[str]) -> None:
        self.ws = ws
        self.prefixes = prefixes
        self.info: dict[str, Any] | None = None
        self.channels: dict[int, dict[str, Any]] = {}
        self.validators: dict[int, Draft202012Validator] = {}
        self.subscribed: dict[int, int] = {}  # subscription id -> channel id
        self.next_subscription = 100
        self.counts: dict[str, int] = {}
        self.invalid: list[str] = []
        self.times: list[int] = []
        self.statuses: list[dict[str, Any]] = []
        self.services: list[dict[str, Any]] = []
        self.playback: list[dict[str, Any]] = []
        self.responses: list[dict[str, Any]] = []
        self.failures: list[dict[str, Any]] = []
        self.messages: list[dict[str, Any]] = []  # (topic, time, payload) of every message

    def receive(self, timeout: float) -> None:
        data = self.ws.recv(timeout=timeout)
        if isinstance(data, str):
            self.text(json.loads(data))
        else:
            self.binary(data)

    def text(self, message: dict[str, Any]) -> None:
        op = message["op"]
        if op == "serverInfo":
            self.info = message
        elif op == "advertise":
            fresh = []
            for channel in message["channels"]:
                assert channel["encoding"] == "json", channel
                assert channel["schemaEncoding"] == "jsonschema", channel
                self.channels[channel["id"]] = channel
                self.validators[channel["id"]] = Draft202012Validator(json.loads(channel["schema"]))
                if not self.prefixes or any(channel["topic"].startswith(p) for p in self.prefixes):
                    fresh.append(channel["id"])
            self.subscribe(fresh)
        elif op == "advertiseServices":
            self.services.extend(message["services"])
        elif op == "status":
            self.statuses.append(message)
        elif op == "serviceCallFailure":
            self.failures.append(message)

    def subscribe(self, channel_ids: list[int]) -> None:
        subscriptions = []
        for channel_id in channel_ids:
            self.subscribed[self.next_subscription] = channel_id
            subscriptions.append({"id": self.next_subscription, "channelId": channel_id})
            self.next_subscription += 1
        if subscriptions:
            self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def binary(self, data: bytes) -> None:
        opcode = data[0]
        if opcode == 1:
            subscription, stamp = struct.unpack_from("<IQ", data, 1)
            payload = json.loads(data[13:])
            channel = self.channels[self.subscribed[subscription]]
            topic = channel["topic"]
            self.counts[topic] = self.counts.get(topic, 0) + 1
            for error in self.validators[channel["id"]].iter_errors(payload):
                self.invalid.append(f"{topic}: {error.message} at {list(error.absolute_path)}")
            self.messages.append({"topic": topic, "time": stamp, "payload": payload})
        elif opcode == 2:
            self.times.append(struct.unpack_from("<Q", data, 1)[0])
        elif opcode == 3:
            service, call, length = struct.unpack_from("<III", data, 1)
            encoding = data[13 : 13 + length].decode()
            self.responses.append(
                {"service": service, "call": call, "encoding": encoding, "payload": json.loads(data[13 + length :])}
            )
        elif opcode == 5:
            status, current, speed, did_seek, length = struct.unpack_from("<BQfBI", data, 1)
            request = data[19 : 19 + length].decode()
            self.playback.append(
                {"status": status, "time": current, "speed": speed, "did_seek": bool(did_seek), "request_id": request}
            )
        else:
            raise AssertionError(f"unknown server opcode {opcode}")

    def until(self, done: Any, what: str) -> None:
        deadline = time.monotonic() + SECONDS
        while not done():
            left = deadline - time.monotonic()
            if left <= 0:
                raise SystemExit(f"timed out waiting for {what}")
            self.receive(left)

    def count(self, prefix: str) -> int:
        return sum(n for topic, n in self.counts.items() if topic.startswith(prefix))


def playback_request(command: int, speed: float, seek_ns: int | None, request_id: str) -> bytes:
    """Binary opcode 3: command (0 play, 1 pause), f32 speed, u8 had seek, u64 seek time, u32 + id."""
    rid = request_id.encode()
    head = struct.pack("<BBfBQI", 3, command, speed, seek_ns is not None, seek_ns or 0, len(rid))
    return head + rid


def service_call(service_id: int, call_id: int, request: dict[str, Any]) -> bytes:
    """Binary opcode 2: u32 service id, u32 call id, u32 encoding length, encoding, payload."""
    return struct.pack("<BIII", 2, service_id, call_id, 4) + b"json" + json.dumps(request).encode()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("url")
    parser.add_argument("--subprotocol", required=True)
    parser.add_argument("--token")
    parser.add_argument("--messages", type=int, default=10, help="to wait for, per --wait prefix")
    parser.add_argument("--topic", action="append", default=[], help="subscribe to topics starting so (all without)")
    parser.add_argument("--wait", action="append", default=[], help="topic prefixes to wait for (default: --topic)")
    parser.add_argument("--seek-ns", type=int)
    parser.add_argument("--call", nargs=2, metavar=("SERVICE", "JSON"), action="append", default=[])
    args = parser.parse_args()
    headers = {"Authorization": f"Bearer {args.token}"} if args.token else {}
    # No keepalive pings: validating every message, this client may fall behind a fast session, and
    # a pong queued behind the backlog would time out (a viewer that keeps up never needs them).
    with connect(
        args.url, subprotocols=[args.subprotocol], additional_headers=headers, max_size=None, ping_interval=None
    ) as ws:
        viewer = Viewer(ws, args.topic)
        first = json.loads(ws.recv(timeout=SECONDS))
        assert first["op"] == "serverInfo", first  # the spec: always sent first
        viewer.text(first)
        wanted = args.wait or args.topic or ["/"]
        viewer.until(lambda: all(viewer.count(p) >= args.messages for p in wanted), "messages")
        report: dict[str, Any] = {"subprotocol": ws.subprotocol}
        calls = []
        for name, body in args.call:
            service = next(s for s in viewer.services if s["name"] == name)
            call_id = 7000 + len(viewer.responses) + len(viewer.failures)
            request = json.loads(body)
            # the advertised request schema says whether the call is well formed; sent either way
            checker = Draft202012Validator(json.loads(service["request"]["schema"]))
            calls.append({"name": name, "call": call_id, "request_valid": checker.is_valid(request)})
            ws.send(service_call(service["id"], call_id, request))
            viewer.until(
                lambda c=call_id: (
                    any(r["call"] == c for r in viewer.responses) or any(f["callId"] == c for f in viewer.failures)
                ),
                f"the answer to {name}",
            )
            answer = next((r for r in viewer.responses if r["call"] == call_id), None)
            if answer is not None:
                response = Draft202012Validator(json.loads(service["response"]["schema"]))
                for error in response.iter_errors(answer["payload"]):
                    viewer.invalid.append(f"{name} response: {error.message}")
        report["calls"] = calls
        if args.seek_ns is not None:
            before = len(viewer.messages)
            ws.send(playback_request(1, 1.0, args.seek_ns, "seek-1"))
            viewer.until(lambda: any(p["request_id"] == "seek-1" for p in viewer.playback), "the seek's state")
            answered = len(viewer.messages)
            viewer.until(lambda: len(viewer.messages) > answered + args.messages, "messages after the seek")
            report["before_seek"] = before
            report["after_seek"] = viewer.messages[answered:]
            ws.send(playback_request(0, 2.0, None, "play-1"))
            viewer.until(lambda: any(p["request_id"] == "play-1" for p in viewer.playback), "the play's state")
        report.update(
            server_info=viewer.info,
            channels=[{k: c[k] for k in ("id", "topic", "schemaName")} for c in viewer.channels.values()],
            counts=viewer.counts,
            invalid=viewer.invalid,
            times=viewer.times,
            statuses=viewer.statuses,
            services=[s["name"] for s in viewer.services],
            playback=viewer.playback,
            responses=viewer.responses,
            failures=viewer.failures,
            first_messages={m["topic"]: m for m in reversed(viewer.messages)},
        )
    json.dump(report, sys.stdout)


if __name__ == "__main__":
    main()
