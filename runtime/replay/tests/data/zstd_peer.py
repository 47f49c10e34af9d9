#!/usr/bin/env python3
"""Regenerates zstd_peer.mcap: a recording in the format of docs/recording.md written by a
peer, the Python `mcap` package (pip install mcap==1.6.0 zstandard), whose writer
compresses chunks with zstd when `zstandard` is installed. One vehicle `usv0` with a float
`speed` set ten times a second for two seconds (speed = step / 10). Run from this folder:
python3 zstd_peer.py"""

from mcap.writer import Writer, CompressionType

START_NS = 1_763_875_200_000_000_000

with open("zstd_peer.mcap", "wb") as f:
    w = Writer(f, compression=CompressionType.ZSTD, chunk_size=2048)
    w.start(profile="mocu", library="python mcap 1.6.0")
    w.add_metadata("mocu", {"format": "1", "start_ns": str(START_NS), "clock": "manual"})
    so = w.register_schema("mocu.ObjectChange", "jsonschema", b'{"type": "object"}')
    sp = w.register_schema("mocu.PropertyChange", "jsonschema", b'{"type": "object"}')
    objects = w.register_channel("/world/object", "json", so)
    props = w.register_channel("/world/property", "json", sp)
    seq = 0

    def put(channel, t, data):
        global seq
        seq += 1
        w.add_message(channel, log_time=t, publish_time=t, sequence=seq, data=data)

    put(objects, START_NS, b'{"op":"created","guid":2,"parent":1,"index":0,"path":"root.vehicles","name":"vehicles","type":"vehicles"}')
    put(objects, START_NS, b'{"op":"created","guid":3,"parent":2,"index":0,"path":"root.vehicles.usv0","name":"usv0","type":"vehicle","subtype":"usv"}')
    put(props, START_NS, b'{"op":"created","object":3,"name":"speed","kind":"float","value":0.0,"meta":{"kind":"float","units":"m/s"}}')
    for i in range(1, 21):
        t = START_NS + i * 100_000_000
        put(props, t, b'{"op":"set","object":3,"name":"speed","kind":"float","value":%r}' % (i / 10))
    w.finish()
