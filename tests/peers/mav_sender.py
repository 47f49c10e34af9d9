#!/usr/bin/env python3
"""Crafted and hostile MAVLink 2 senders played by pymavlink, for Mocu's tests
(runtime/mavlink/tests/crafted_peers.rs). Each mode sends to udpout:127.0.0.1:PORT and exits.

Modes:
  newer     HEARTBEATs of a vehicle newer than the common dialect (MAV_TYPE 142, autopilot 99,
            MAV_STATE 17), GPS_RAW_INT with fix type 9 and a position.
  signed    HEARTBEATs signed with --key until a HEARTBEAT from the OCU (system 255) arrives
            that pymavlink accepts as signed with the same key; prints "verified N" (the good
            signatures pymavlink counted).
  wrongkey  HEARTBEATs signed with --key (the wrong one, on purpose); then listens.
  unsigned  HEARTBEATs without a signature; then listens.
  incompat  HEARTBEATs with an unknown incompatibility flag (0x04); then listens.
  flood     one HEARTBEAT from each of --count system ids (a spoofed flood); then listens.
After the listening modes it prints "replies N": the datagrams the OCU sent back.
Keys: the SHA-256 of the --key text (as MAVProxy's `signing setup` derives them).
"""
import argparse
import hashlib
import os
import struct
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402
from pymavlink.generator import mavcrc  # noqa: E402

m = mavutil.mavlink

ap = argparse.ArgumentParser()
ap.add_argument("--port", type=int, required=True)
ap.add_argument("--mode", required=True)
ap.add_argument("--sysid", type=int, default=1)
ap.add_argument("--key", default="")
ap.add_argument("--count", type=int, default=5)
ap.add_argument("--listen", type=float, default=1.5)
args = ap.parse_args()

conn = mavutil.mavlink_connection(
    f"udpout:127.0.0.1:{args.port}", source_system=args.sysid, source_component=1, dialect="common"
)


def say(*parts):
    print(*parts, flush=True)


def quad_heartbeat():
    conn.mav.heartbeat_send(
        m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0,
        m.MAV_STATE_ACTIVE,
    )


def listen():
    """Counts whatever comes back for a while (the OCU must send nothing)."""
    n = 0
    end = time.time() + args.listen
    conn.port.settimeout(0.1)
    while time.time() < end:
        try:
            data, _ = conn.port.recvfrom(65536)
            n += 1 if data else 0
        except OSError:
            pass
    say("replies", n)


if args.mode in ("signed", "wrongkey"):
    key = hashlib.sha256(args.key.encode()).digest()
    conn.setup_signing(key, sign_outgoing=True, allow_unsigned_callback=None, link_id=1)

if args.mode == "newer":
    for _ in range(3):
        conn.mav.heartbeat_send(142, 99, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 5, 17)
    conn.mav.gps_raw_int_send(0, 9, int(32.7157e7), int(-117.1611e7), 1000, 90, 120, 0, 0, 14)
    conn.mav.global_position_int_send(0, int(32.7157e7), int(-117.1611e7), 1000, 500, 0, 0, 0, 0)
    say("sent")
elif args.mode == "signed":
    end = time.time() + 30
    verified = 0
    while time.time() < end and verified == 0:
        quad_heartbeat()
        msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.2)
        if msg is not None and msg.get_srcSystem() == 255:
            verified = conn.mav.signing.goodsig_count
    say("verified", verified)
elif args.mode in ("wrongkey", "unsigned"):
    for _ in range(args.count):
        quad_heartbeat()
    listen()
elif args.mode == "incompat":
    for seq in range(args.count):
        msg = m.MAVLink_heartbeat_message(
            m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, m.MAV_STATE_ACTIVE, 3
        )
        frame = bytearray(msg.pack(conn.mav))
        frame[2] |= 0x04
        frame[4] = seq
        crc = mavcrc.x25crc(bytes(frame[1:-2]))
        crc.accumulate(struct.pack("B", msg.crc_extra))
        frame[-2:] = struct.pack("<H", crc.crc)
        conn.write(bytes(frame))
    listen()
elif args.mode == "flood":
    for sysid in range(1, args.count + 1):
        conn.mav.srcSystem = sysid
        quad_heartbeat()
    listen()
else:
    raise SystemExit(f"unknown mode {args.mode}")
