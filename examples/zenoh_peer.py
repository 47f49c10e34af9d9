#!/usr/bin/env python3
"""A peer of Mocu's distributed world model written with eclipse-zenoh alone
(docs/distribution.md): reads a vehicle's properties and calls one of its methods.

    pip install eclipse-zenoh==1.10.2
    python3 examples/zenoh_peer.py ENDPOINT VEHICLE METHOD [ARG...]
    python3 examples/zenoh_peer.py tcp/127.0.0.1:7447 usv1 start_engine

ARGs are JSON (true, 3, 2.5, "text"). Prints one JSON document on stdout:
{"site": ..., "object": "vehicles/usv1", "properties": {"nav/speed": 1.2, ...},
 "units": {"nav/speed": "m/s", ...}, "call": "start_engine", "outcome": {...}}.
Exit 0 when the call came back with an outcome (whatever it is), 1 otherwise.
"""

import json
import sys

import zenoh


def typed(x):
    """A JSON argument as a typed value of the payload format."""
    if isinstance(x, bool):
        return {"kind": "bool", "value": x}
    if isinstance(x, int):
        return {"kind": "int", "value": x}
    if isinstance(x, float):
        return {"kind": "float", "value": x}
    if isinstance(x, str):
        return {"kind": "string", "value": x}
    if isinstance(x, list):
        return {"kind": "list", "value": [typed(e) for e in x]}
    raise ValueError(f"cannot send {x!r}")


def main():
    if len(sys.argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    endpoint, vehicle, method = sys.argv[1:4]
    args = [typed(json.loads(a)) for a in sys.argv[4:]]

    conf = zenoh.Config()
    # A client of the adapter: open() fails at once if nobody listens there.
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(conf) as session:
        # 1. The vehicle's properties: one query answered from the owner's snapshot.
        site, props, units = None, {}, {}
        prefix = None
        for reply in session.get(f"mocu/*/prop/vehicles/{vehicle}/**", timeout=10.0):
            if reply.ok is None:
                continue
            key = str(reply.ok.key_expr).split("/")
            # mocu/<site>/prop/vehicles/<vehicle>/<path...>/<name>
            site = key[1]
            prefix = "/".join(key[3:5])
            body = json.loads(reply.ok.payload.to_bytes())
            name = "/".join(key[5:])
            props[name] = body["value"]["value"]
            if body.get("meta", {}).get("units"):
                units[name] = body["meta"]["units"]
        if site is None:
            print(f"no site publishes vehicles/{vehicle}", file=sys.stderr)
            return 1

        # 2. One of its methods, as a query; the reply is the full outcome.
        outcome = None
        payload = json.dumps({"args": args, "timeout_ms": 5000, "operator": "python"})
        for reply in session.get(
            f"mocu/{site}/call/vehicles/{vehicle}/{method}", payload=payload, timeout=10.0
        ):
            if reply.ok is not None:
                outcome = json.loads(reply.ok.payload.to_bytes())
                break
        print(json.dumps({
            "site": site,
            "object": prefix,
            "properties": props,
            "units": units,
            "call": method,
            "outcome": outcome,
        }, sort_keys=True))
        return 0 if outcome is not None else 1


if __name__ == "__main__":
    sys.exit(main())
