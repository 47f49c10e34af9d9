#!/usr/bin/env python3
"""A MAVLink 2 vehicle played by pymavlink, for Mocu's tests (tests/mavlink_peer.rs).

Sends HEARTBEAT and SYS_STATUS at 1 Hz, GLOBAL_POSITION_INT, ATTITUDE, VFR_HUD and
GPS_RAW_INT at 10 Hz to udpout:127.0.0.1:PORT, answers COMMAND_LONG / COMMAND_INT with
COMMAND_ACK and plays the vehicle side of the mission upload protocol.

Behaviour the tests rely on:
  * arm/disarm (400), set mode (176), return to launch (20), reposition (192): accepted.
  * land (21): refused with MAV_RESULT_DENIED.
  * other commands: MAV_RESULT_UNSUPPORTED.
  * at start: one garbage datagram and one frame with an unknown message id.
  * MISSION_WRITE_PARTIAL_LIST: the items start..=end asked for and written over the
    mission held (a range outside it: MAV_MISSION_INVALID_SEQUENCE).
  * stdin line "refuse_partial": from then on a partial write is refused with
    MAV_MISSION_UNSUPPORTED (an autopilot without partial writes).
  * stdin line "silence S": send nothing for S seconds (link loss), then resume.
  * stdin line "quit" (or EOF): exit.
  * --gcs-control N: the vehicle speaks MAVLink's GCS operator-control protocol (development
    dialect): CONTROL_STATUS (message 512, system manager) at 1 Hz and at each change, GCS N
    in control at start (0: none), takeover not allowed; MAV_CMD_REQUEST_OPERATOR_CONTROL
    (32100) grants a request when nobody holds it (ACCEPTED, else FAILED) and a release by
    the holder. stdin line "gcs_release": the holding GCS lets go.
    Prints "control N" at each change of the GCS in control.
Prints "ready", "mission N", "mission_item SEQ LAT LON ALT", "partial START END",
"partial_item SEQ LAT LON ALT", "partial_refused START END" lines on stdout.
"""
import argparse
import os
import sys
import threading
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

m = mavutil.mavlink

ap = argparse.ArgumentParser()
ap.add_argument("--port", type=int, required=True)
ap.add_argument("--sysid", type=int, default=1)
ap.add_argument("--gcs-control", type=int, default=None)
args = ap.parse_args()

conn = mavutil.mavlink_connection(
    f"udpout:127.0.0.1:{args.port}", source_system=args.sysid, source_component=1, dialect="common"
)

state = {"armed": False, "mode": 0, "silent_until": 0.0, "quit": False, "refuse_partial": False,
         "gcs": args.gcs_control}

# MAVLink's operator-control protocol is in the development dialect, which pymavlink 2.4.50
# lacks: CONTROL_STATUS is framed here as the spec defines it (MAVLink 2, CRC_EXTRA from its
# fields, uint8 flags, uint8 gcs_main, uint8[10] gcs_secondary).
MAV_CMD_REQUEST_OPERATOR_CONTROL = 32100
CONTROL_STATUS_ID = 512
FLAG_SYSTEM_MANAGER = 1


def crc_extra(name, fields):
    from pymavlink.generator.mavcrc import x25crc
    crc = x25crc()
    crc.accumulate_str(name + " ")
    for ftype, fname, length in fields:
        crc.accumulate_str(ftype + " ")
        crc.accumulate_str(fname + " ")
        if length:
            crc.accumulate([length])
    return (crc.crc & 0xFF) ^ (crc.crc >> 8)


CONTROL_STATUS_EXTRA = crc_extra(
    "CONTROL_STATUS", [("uint8_t", "flags", 0), ("uint8_t", "gcs_main", 0), ("uint8_t", "gcs_secondary", 10)]
)
control_seq = [0]


def send_control_status():
    from pymavlink.generator.mavcrc import x25crc
    payload = bytes([FLAG_SYSTEM_MANAGER, state["gcs"]] + [0] * 10).rstrip(b"\0") or b"\0"
    header = bytes([len(payload), 0, 0, control_seq[0] & 0xFF, args.sysid, 1,
                    CONTROL_STATUS_ID & 0xFF, (CONTROL_STATUS_ID >> 8) & 0xFF, 0])
    control_seq[0] += 1
    crc = x25crc(header + payload)
    crc.accumulate([CONTROL_STATUS_EXTRA])
    conn.write(bytes([0xFD]) + header + payload + bytes([crc.crc & 0xFF, crc.crc >> 8]))

lock = threading.Lock()


def say(*parts):
    print(*parts, flush=True)


def stdin_commands():
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "silence":
            with lock:
                state["silent_until"] = time.time() + float(words[1])
            say("silenced", words[1])
        elif words[0] == "refuse_partial":
            state["refuse_partial"] = True
            say("refusing partial writes")
        elif words[0] == "gcs_release":
            with lock:
                state["gcs"] = 0
            say("control", 0)
            send_control_status()
        elif words[0] == "quit":
            break
    state["quit"] = True


threading.Thread(target=stdin_commands, daemon=True).start()

# Malformed and unknown packets first: the OCU must count them and carry on.
conn.write(b"this is not mavlink")
unknown = bytes([0xFD, 3, 0, 0, 0, args.sysid, 1, 0x99, 0x99, 0x00, 1, 2, 3, 0x12, 0x34])
conn.write(unknown)

mission = {"count": 0, "next": 0, "items": []}
# A partial write under way: the next item asked for and the last of the range.
partial = None
t0 = time.time()
next_slow = 0.0
next_fast = 0.0
say("ready")

while not state["quit"]:
    now = time.time()
    silent = now < state["silent_until"]
    if not silent and now >= next_slow:
        next_slow = now + 1.0
        base = m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if state["armed"]:
            base |= m.MAV_MODE_FLAG_SAFETY_ARMED
        conn.mav.heartbeat_send(
            m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA, base, state["mode"], m.MAV_STATE_ACTIVE
        )
        conn.mav.sys_status_send(0, 0, 0, 250, 12600, 1500, 87, 0, 0, 0, 0, 0, 0)
        if state["gcs"] is not None:
            send_control_status()
    if not silent and now >= next_fast:
        next_fast = now + 0.1
        ms = int((now - t0) * 1000)
        conn.mav.global_position_int_send(
            ms, int(32.7157 * 1e7), int(-117.1611 * 1e7), 112345, 12345, 300, 400, -50, 9000
        )
        conn.mav.attitude_send(ms, 0.1, -0.05, 1.5708, 0.0, 0.0, 0.0)
        conn.mav.vfr_hud_send(5.5, 5.0, 90, 42, 112.3, 0.5)
        conn.mav.gps_raw_int_send(
            ms * 1000, 3, int(32.7157 * 1e7), int(-117.1611 * 1e7), 112345, 90, 120, 500, 9000, 11
        )

    msg = conn.recv_match(blocking=True, timeout=0.02)
    if msg is None or silent:
        continue
    t = msg.get_type()
    if t in ("COMMAND_LONG", "COMMAND_INT"):
        cmd = msg.command
        if cmd == m.MAV_CMD_COMPONENT_ARM_DISARM:
            state["armed"] = msg.param1 >= 0.5
            result = m.MAV_RESULT_ACCEPTED
        elif cmd == m.MAV_CMD_DO_SET_MODE:
            state["mode"] = int(msg.param2)
            result = m.MAV_RESULT_ACCEPTED
        elif cmd in (m.MAV_CMD_NAV_RETURN_TO_LAUNCH, m.MAV_CMD_DO_REPOSITION):
            result = m.MAV_RESULT_ACCEPTED
        elif cmd == m.MAV_CMD_NAV_LAND:
            result = m.MAV_RESULT_DENIED
        elif cmd == MAV_CMD_REQUEST_OPERATOR_CONTROL and state["gcs"] is not None:
            gcs = int(msg.param4) or msg.get_srcSystem()
            with lock:
                if msg.param1 >= 0.5 and state["gcs"] in (0, gcs):
                    state["gcs"], result = gcs, m.MAV_RESULT_ACCEPTED
                elif msg.param1 < 0.5 and state["gcs"] == gcs:
                    state["gcs"], result = 0, m.MAV_RESULT_ACCEPTED
                else:
                    result = m.MAV_RESULT_FAILED
            if result == m.MAV_RESULT_ACCEPTED:
                say("control", state["gcs"])
        else:
            result = m.MAV_RESULT_UNSUPPORTED
        say("command", cmd, result)
        conn.mav.command_ack_send(cmd, result)
        if cmd == MAV_CMD_REQUEST_OPERATOR_CONTROL and state["gcs"] is not None:
            send_control_status()
    elif t == "MISSION_COUNT":
        partial = None
        mission = {"count": msg.count, "next": 0, "items": []}
        say("mission", msg.count)
        conn.mav.mission_request_int_send(msg.get_srcSystem(), msg.get_srcComponent(), 0)
    elif t == "MISSION_WRITE_PARTIAL_LIST":
        src, comp = msg.get_srcSystem(), msg.get_srcComponent()
        start, end = msg.start_index, msg.end_index
        if state["refuse_partial"]:
            say("partial_refused", start, end)
            conn.mav.mission_ack_send(src, comp, m.MAV_MISSION_UNSUPPORTED)
        elif not (0 <= start <= end < len(mission["items"])):
            say("partial_invalid", start, end)
            conn.mav.mission_ack_send(src, comp, m.MAV_MISSION_INVALID_SEQUENCE)
        else:
            partial = {"next": start, "end": end}
            say("partial", start, end)
            conn.mav.mission_request_int_send(src, comp, start)
    elif t == "MISSION_ITEM_INT" and partial is not None:
        src, comp = msg.get_srcSystem(), msg.get_srcComponent()
        if msg.seq == partial["next"]:
            mission["items"][msg.seq] = msg
            say("partial_item", msg.seq, msg.x / 1e7, msg.y / 1e7, msg.z)
            partial["next"] += 1
        if partial["next"] <= partial["end"]:
            conn.mav.mission_request_int_send(src, comp, partial["next"])
        else:
            partial = None
            conn.mav.mission_ack_send(src, comp, m.MAV_MISSION_ACCEPTED)
    elif t == "MISSION_ITEM_INT":
        if msg.seq == mission["next"]:
            mission["items"].append(msg)
            say("mission_item", msg.seq, msg.x / 1e7, msg.y / 1e7, msg.z)
            mission["next"] += 1
        if mission["next"] < mission["count"]:
            conn.mav.mission_request_int_send(msg.get_srcSystem(), msg.get_srcComponent(), mission["next"])
        else:
            conn.mav.mission_ack_send(msg.get_srcSystem(), msg.get_srcComponent(), m.MAV_MISSION_ACCEPTED)
