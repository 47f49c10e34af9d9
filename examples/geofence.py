#!/usr/bin/env python3
"""A Mocu module in Python (docs/modules.md): a geofence watcher that joins the OCU's world
model over Zenoh with eclipse-zenoh alone (docs/distribution.md, key space and payloads).

It follows every vehicle's position (nav.x, nav.y, metres in the local frame) and, when
one leaves its zone, raises an alert and calls the vehicle's `stop()`. The zone is a circle:
`--zone X,Y,R` for one fixed circle, or by default a leash of `--radius R` metres around
where each vehicle was first seen.

It publishes its own object `root.geofence` (site `MOCU_MODULE`, default `geofence`):
`alerts` (how many), `last_alert` (the text), `outside` (the vehicles out of their zone),
`stale` (false; the OCU raises it while this process is down). Alerts also go to stderr.

Run from a profile:

    [modules.geofence]
    kind = "process"
    command = ["python3", "examples/geofence.py", "--radius", "150"]

or by hand against an OCU listening on ENDPOINT:

    MOCU_CONNECT=tcp/127.0.0.1:7447 python3 examples/geofence.py --radius 150
"""

import argparse
import json
import math
import os
import sys
import threading

import zenoh


def typed(x):
    """A value of the payload format."""
    if isinstance(x, bool):
        return {"kind": "bool", "value": x}
    if isinstance(x, int):
        return {"kind": "int", "value": x}
    if isinstance(x, str):
        return {"kind": "string", "value": x}
    if isinstance(x, list):
        return {"kind": "list", "value": [typed(e) for e in x]}
    raise ValueError(f"cannot send {x!r}")


class Fence:
    """This module's object on the key space: its record, its properties, its snapshot."""

    GUID = 1

    def __init__(self, session, site):
        self.session = session
        self.site = site
        self.lock = threading.Lock()
        self.props = {"stale": False, "alerts": 0, "last_alert": "", "outside": []}
        self.record = json.dumps({"guid": self.GUID, "name": "geofence", "type": "geofence",
                                  "subtype": "", "methods": []})
        # The snapshot a joining OCU asks for, then the token that makes it ask.
        self.queryables = [
            session.declare_queryable(f"mocu/{site}/obj/**", self.answer_objects),
            session.declare_queryable(f"mocu/{site}/prop/**", self.answer_props),
        ]
        session.put(f"mocu/{site}/obj/geofence", self.record)
        for name in self.props:
            self.put(name, meta=True)
        self.token = session.liveliness().declare_token(f"mocu/{site}/alive")

    def payload(self, name, meta):
        body = {"object": self.GUID, "value": typed(self.props[name])}
        if meta:
            body["meta"] = {"kind": body["value"]["kind"]}
        return json.dumps(body)

    def put(self, name, meta=False):
        self.session.put(f"mocu/{self.site}/prop/geofence/{name}", self.payload(name, meta))

    def set(self, name, value):
        with self.lock:
            self.props[name] = value
            self.put(name)

    def answer_objects(self, query):
        query.reply(f"mocu/{self.site}/obj/geofence", self.record)

    def answer_props(self, query):
        with self.lock:
            for name in self.props:
                key = f"mocu/{self.site}/prop/geofence/{name}"
                query.reply(key, self.payload(name, meta=True))


def stop(session, me, site, vehicle):
    """Calls `stop()` on the vehicle at the site that owns it; returns the outcome."""
    body = json.dumps({"args": [], "timeout_ms": 5000, "operator": me, "site": me})
    for reply in session.get(f"mocu/{site}/call/vehicles/{vehicle}/stop", payload=body,
                             timeout=10.0):
        if reply.ok is not None:
            return json.loads(reply.ok.payload.to_bytes())
    return {"outcome": "failed", "reason": "no answer"}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--radius", type=float, default=150.0,
                    help="leash radius around each vehicle's first position (m)")
    ap.add_argument("--zone", help="one circle for every vehicle: X,Y,R (m)")
    ap.add_argument("--connect", default=os.environ.get("MOCU_CONNECT"),
                    help="the OCU's Zenoh endpoint (default: $MOCU_CONNECT)")
    args = ap.parse_args()
    if not args.connect:
        print("geofence: no endpoint (--connect or MOCU_CONNECT)", file=sys.stderr)
        return 2
    fixed = [float(v) for v in args.zone.split(",")] if args.zone else None
    me = os.environ.get("MOCU_MODULE", "geofence")

    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([args.connect]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(conf) as session:
        fence = Fence(session, me)
        positions = session.declare_subscriber("mocu/*/prop/vehicles/*/nav/*")
        print(f"geofence: joined {args.connect} as site `{me}`", file=sys.stderr, flush=True)
        seen, zones, outside = {}, {}, set()
        for sample in positions:
            key = str(sample.key_expr).split("/")
            # mocu/<site>/prop/vehicles/<vehicle>/nav/<x|y>
            if len(key) != 7 or key[6] not in ("x", "y"):
                continue
            site, vehicle, axis = key[1], key[4], key[6]
            try:
                value = float(json.loads(sample.payload.to_bytes())["value"]["value"])
            except (ValueError, KeyError, TypeError):
                continue
            pos = seen.setdefault(vehicle, {})
            pos[axis] = value
            if "x" not in pos or "y" not in pos:
                continue
            zone = fixed or zones.setdefault(vehicle, (pos["x"], pos["y"], args.radius))
            out = math.hypot(pos["x"] - zone[0], pos["y"] - zone[1]) > zone[2]
            if out and vehicle not in outside:
                outside.add(vehicle)
                text = (f"{vehicle} left its zone ({zone[2]:g} m around "
                        f"{zone[0]:.0f}, {zone[1]:.0f}): stopping it")
                print(f"geofence: ALERT {text}", file=sys.stderr, flush=True)
                fence.set("alerts", fence.props["alerts"] + 1)
                fence.set("last_alert", text)
                fence.set("outside", sorted(outside))
                outcome = stop(session, me, site, vehicle)
                print(f"geofence: {vehicle}.stop() {json.dumps(outcome)}",
                      file=sys.stderr, flush=True)
            elif not out and vehicle in outside:
                outside.discard(vehicle)
                fence.set("outside", sorted(outside))
    return 0


if __name__ == "__main__":
    sys.exit(main())
