#!/usr/bin/env python3
"""An independent reader of `mocu run --record` files (docs/recording.md), with the PyPI
`mcap` package (pinned in .ci/run). Prints one JSON report on stdout:

  {"summary": bool,            # the file has its summary and footer (a finished recording)
   "complete": bool,           # every record read without error (false: a torn end)
   "error": str | null,        # what stopped the reading, if anything
   "metadata": {...},          # the `mocu` metadata record
   "attachments": [names],
   "channels": {topic: {"schema", "schema_encoding", "encoding", "count",
                        "monotonic": log_time never decreases,
                        "decoded": every message decodes (JSON; CDR on /world/values,
                                   /video/*, /image/* and /camera/*),
                        "first_ns", "last_ns"}},
   "values": int,              # entries in /world/values batches
   "properties": {path: [[log_time_ns, kind, value], ...]},   # for each --property PATH,
                                                              # /world/property and the
                                                              # /world/values entries
   "calls": [[path.method, op, outcome or null], ...],         # /calls, in order (an
                                                               # outcome named by its call)
   "frames": {topic: {"count", "format", "first_bytes_hex", "size", "timestamp_ns"}}}
                               # /video/*, /image/* (format: h264, jpeg) and /camera/*
                               # (format: rgb8, rgba8; with width and height)

Usage: read_recording.py FILE.mcap [--property PATH]...

A finished file is read through its index (the seeking reader); one without a summary (a
killed recording) is read linearly up to the first record that is cut short.
"""

import base64
import json
import struct
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
        "values": 0,
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
    # Batch entries name their property by id: resolved now that every id is known.
    ids = report.pop("_ids", {})
    for t, pid, kind, value in report.pop("_entries", []):
        path = ids.get(pid)
        if path in report["properties"]:
            report["properties"][path].append([t, kind, value])
    for rows in report["properties"].values():
        rows.sort(key=lambda r: r[0])
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


def count_frame(report, topic, **first):
    """Counts a camera frame on `topic`; the first one's description is kept."""
    fr = report["frames"].setdefault(topic, {"count": 0})
    fr["count"] += 1
    if fr["count"] == 1:
        fr.update(first)


def take(report, schema, channel, message):
    c = report["channels"].setdefault(
        channel.topic,
        {
            "schema": schema.name if schema else None,
            "schema_encoding": schema.encoding if schema else None,
            "encoding": channel.message_encoding,
            "count": 0,
            "monotonic": True,
            "decoded": True,
            "first_ns": message.log_time,
            "last_ns": message.log_time,
        },
    )
    c["count"] += 1
    if message.log_time < c["last_ns"]:
        c["monotonic"] = False
    c["last_ns"] = message.log_time
    topic = channel.topic
    if channel.message_encoding == "cdr" and schema and schema.name == "foxglove_msgs/msg/RawImage":
        try:
            image = raw_image(message.data)
        except (ValueError, struct.error, UnicodeDecodeError):
            c["decoded"] = False
            return
        count_frame(
            report,
            topic,
            format=image["encoding"],
            width=image["width"],
            height=image["height"],
            first_bytes_hex=image["data"][:4].hex(),
            size=len(image["data"]),
            timestamp_ns=image["timestamp_ns"],
        )
        return
    if channel.message_encoding == "cdr" and schema and schema.name in COMPRESSED:
        try:
            unit = compressed(message.data)
        except (ValueError, struct.error, UnicodeDecodeError):
            c["decoded"] = False
            return
        count_frame(
            report,
            topic,
            format=unit["format"],
            first_bytes_hex=unit["data"][:4].hex(),
            size=len(unit["data"]),
            timestamp_ns=unit["timestamp_ns"],
        )
        return
    if channel.message_encoding == "cdr":
        try:
            entries = property_values(message.data)
        except (ValueError, struct.error):
            c["decoded"] = False
            return
        report["values"] += len(entries)
        report.setdefault("_entries", []).extend(entries)
        return
    try:
        body = json.loads(message.data)
    except ValueError:
        c["decoded"] = False
        return
    if topic == "/world/property":
        if "id" in body:
            report.setdefault("_ids", {})[body["id"]] = body.get("path")
        if body.get("op") != "deleted" and body.get("path") in report["properties"]:
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


KINDS = {0: "float", 1: "int", 2: "bool"}


class Cdr:
    """Little-endian CDR: alignment counted from after the 4-byte encapsulation header."""

    def __init__(self, data):
        if data[:2] != b"\x00\x01":
            raise ValueError("not little-endian CDR")
        self.data, self.at = data, 4

    def take(self, align, n):
        self.at += (align - (self.at - 4) % align) % align
        if self.at + n > len(self.data):
            raise ValueError("cut short")
        self.at += n
        return self.data[self.at - n : self.at]

    def u32(self):
        return struct.unpack("<I", self.take(4, 4))[0]

    def string(self):
        b = self.take(1, self.u32())
        if not b.endswith(b"\x00"):
            raise ValueError("a string without its NUL")
        return b[:-1].decode("utf-8")


def raw_image(data):
    """A foxglove_msgs/msg/RawImage (CDR; docs/recording.md, /camera/*)."""
    c = Cdr(data)
    sec, nsec = c.u32(), c.u32()
    frame_id = c.string()
    width, height = c.u32(), c.u32()
    encoding = c.string()
    step = c.u32()
    pixels = c.take(1, c.u32())
    if step * height != len(pixels):
        raise ValueError("rows do not add up to the data")
    return {"timestamp_ns": sec * 1_000_000_000 + nsec, "frame_id": frame_id, "width": width,
            "height": height, "encoding": encoding, "data": pixels}


COMPRESSED = ("foxglove_msgs/msg/CompressedVideo", "foxglove_msgs/msg/CompressedImage")


def compressed(data):
    """A foxglove_msgs/msg/CompressedVideo or CompressedImage with Mocu's unit and arrival_us
    (CDR; docs/recording.md, /video/* and /image/*)."""
    c = Cdr(data)
    sec, nsec = c.u32(), c.u32()
    frame_id = c.string()
    payload = c.take(1, c.u32())
    fmt = c.string()
    unit, arrival_us = struct.unpack("<qq", c.take(8, 16))
    return {"timestamp_ns": sec * 1_000_000_000 + nsec, "frame_id": frame_id, "data": payload,
            "format": fmt, "unit": unit, "arrival_us": arrival_us}


def property_values(data):
    """A /world/values batch (mocu_msgs/msg/PropertyValues, CDR little endian; docs/recording.md):
    [(log_time_ns, id, kind, value), ...]."""
    c = Cdr(data)
    first_seq, first_ns = struct.unpack("<QQ", c.take(8, 16))
    cols = []
    for fmt, size in (("I", 4), ("I", 4), ("I", 4), ("B", 1), ("d", 8)):
        n = c.u32()
        cols.append(struct.unpack(f"<{n}{fmt}", c.take(size, n * size)))
    ids, seqs, dts, kinds, values = cols
    # Format 3: seq empty when the changes are numbered one after the other, kind empty
    # when every entry is a float.
    kinds = kinds or (0,) * len(ids)
    if not len(ids) == len(dts) == len(kinds) == len(values) or len(seqs) not in (0, len(ids)):
        raise ValueError("columns of different lengths")
    out = []
    for i, kind in enumerate(kinds):
        v = values[i]
        v = int(v) if kind == 1 else bool(v) if kind == 2 else v
        out.append((first_ns + dts[i], ids[i], KINDS[kind], v))
    return out


if __name__ == "__main__":
    main(sys.argv)
