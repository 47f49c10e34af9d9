#!/usr/bin/env python3
"""An independent reader of `mocu run --record` files (docs/recording.md), with the PyPI
`mcap` package (pinned in .ci/run). Prints one JSON report on stdout:

  {"summary": bool,            # the file has its summary and footer (a finished recording)
   "complete": bool,           # every record read without error (false: a torn end)
   "error": str | null,        # what stopped the reading, if anything
   "metadata": {...},          # the `mocu` metadata record
   "attachments": [names],
   "channels": {topic: {"schema", "schema_encoding", "encoding", "count",
                        "monotonic": log_time never decreases, "json": every message parses,
                        "first_ns", "last_ns"}},
   "properties": {path: [[log_time_ns, kind, value], ...]},   # for each --property PATH
   "calls": [[path.method, op, outcome or null], ...],         # /calls, in order (an
                                                               # outcome named by its call)
   "frames": {topic: {"count", "format", "first_bytes_hex", "size", "timestamp_ns"}}}

Usage: read_recording.py FILE.mcap [--property PATH]...

A finished file is read through its index (the seeking reader); one without a summary (a
killed recording) is read linearly up to the first record that is cut short.
"""

import base64
import json
import sys

from mcap.reader import SeekingReader
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader


def main(argv):
    path = argv[1]
    wanted = [argv[i + 1] for i, a in enumerate(argv) if a == "--property"]
    report = {
        "summary": False,
        "complete": True,
        "error": None,
        "metadata": {},
        "attachments": [],
        "channels": {},
        "properties": {p: [] for p in wanted},
        "calls": [],
        "frames": {},
    }
    with open(path, "rb") as f:
        try:
            summary = SeekingReader(f).get_summary()
            report["summary"] = summary is not None and len(summary.chunk_indexes) > 0
        except Exception:  # a torn file has no footer to seek from
            report["summary"] = False
        f.seek(0)
        if report["summary"]:
            reader = SeekingReader(f)
            for m in reader.iter_metadata():
                report["metadata"][m.name] = dict(m.metadata)
            for a in reader.iter_attachments():
                report["attachments"].append(a.name)
            f.seek(0)
            messages = SeekingReader(f).iter_messages(log_time_order=False)
        else:
            messages = linear(f)
        try:
            for schema, channel, message in messages:
                take(report, schema, channel, message)
        except Exception as e:  # the torn end of a killed recording
            report["complete"] = False
            report["error"] = f"{type(e).__name__}: {e}"
    report.pop("_calls", None)
    json.dump(report, sys.stdout)
    sys.stdout.write("\n")


def linear(f):
    """Every message in file order, from the records themselves (a killed recording: the
    stream ends with the torn chunk, where this raises)."""
    schemas, channels = {}, {}
    for r in StreamReader(f, skip_magic=False).records:
        if isinstance(r, Schema):
            schemas[r.id] = r
        elif isinstance(r, Channel):
            channels[r.id] = r
        elif isinstance(r, Message):
            ch = channels[r.channel_id]
            yield schemas.get(ch.schema_id), ch, r


def take(report, schema, channel, message):
    c = report["channels"].setdefault(
        channel.topic,
        {
            "schema": schema.name if schema else None,
            "schema_encoding": schema.encoding if schema else None,
            "encoding": channel.message_encoding,
            "count": 0,
            "monotonic": True,
            "json": True,
            "first_ns": message.log_time,
            "last_ns": message.log_time,
        },
    )
    c["count"] += 1
    if message.log_time < c["last_ns"]:
        c["monotonic"] = False
    c["last_ns"] = message.log_time
    try:
        body = json.loads(message.data)
    except ValueError:
        c["json"] = False
        return
    topic = channel.topic
    if topic == "/world/property" and body.get("path") in report["properties"]:
        report["properties"][body["path"]].append([message.log_time, body.get("kind"), body.get("value")])
    elif topic == "/calls":
        names = report.setdefault("_calls", {})
        if body["op"] == "call":
            names[body["id"]] = f'{body["path"]}.{body["method"]}'
        report["calls"].append([names.get(body["id"]), body["op"], body.get("outcome")])
    elif topic.startswith("/video/") or topic.startswith("/image/"):
        fr = report["frames"].setdefault(topic, {"count": 0})
        fr["count"] += 1
        if fr["count"] == 1:
            data = base64.b64decode(body["data"])
            ts = body["timestamp"]
            fr.update(
                format=body["format"],
                first_bytes_hex=data[:4].hex(),
                size=len(data),
                timestamp_ns=ts["sec"] * 1_000_000_000 + ts["nsec"],
            )


if __name__ == "__main__":
    main(sys.argv)
