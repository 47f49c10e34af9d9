"""`mocu lsp` with live values: a real `mocu serve` (the simulator's vehicles, shared over
Zenoh on a free loopback port) and the language server told to connect to it in its
`initializationOptions` (`{"live": {"connect": [ENDPOINT]}}`, docs/editors.md). Completion
offers the objects that exist now (the UGV and UAV the project's schema does not declare),
hover the current value of a property with its units and age.

Run by tests/cli_lsp.rs. Every wait is on a condition (a line the adapter prints, an answer
that has the live objects) under one generous deadline that only a hung test reaches.
"""

import asyncio
import os
import pathlib
import queue
import socket
import subprocess
import threading
import time

import pytest
import pytest_lsp
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient

# `project` is the same fixture (the profile, its schema and the layout in a temporary folder).
from test_mocu_lsp import LAYOUT, at, completion_labels, diagnostics_of, open_layout, project  # noqa: F401

MOCU = os.environ["MOCU_BIN"]
REPO = pathlib.Path(__file__).resolve().parents[3]
# Long enough for a loaded 2-core CI machine; a hang becomes a failure.
PATIENCE = 90.0
VEHICLES = ["usv1", "usv2", "ugv1", "uav1"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def adapter():
    """`mocu serve` on a free port, once it has the simulator's four vehicles: its endpoint."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    proc = subprocess.Popen(
        [MOCU, "serve", "--listen", endpoint, "--mavlink", "off", "--video", "off"],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(l) for l in proc.stderr], daemon=True).start()
    deadline = time.monotonic() + PATIENCE
    seen = []
    try:
        while True:
            line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            seen.append(line)
            if "vehicles: " in line and all(v in line for v in VEHICLES):
                break
    except queue.Empty:
        proc.kill()
        pytest.fail("mocu serve never had its four vehicles; it printed:\n" + "".join(seen))
    yield endpoint
    proc.kill()
    proc.wait()


@pytest_lsp.fixture(config=ClientServerConfig(server_command=[MOCU, "lsp"]))
async def client(lsp_client: LanguageClient, adapter):
    await lsp_client.initialize_session(
        types.InitializeParams(
            capabilities=types.ClientCapabilities(),
            initialization_options={"live": {"connect": [adapter]}},
        )
    )
    yield
    await lsp_client.shutdown_session()


async def until(what: str, ask):
    """Asks `ask()` until it answers something true (the mirror fills as the adapter's
    snapshot arrives); fails only at the deadline."""
    deadline = time.monotonic() + PATIENCE
    while True:
        got = await ask()
        if got:
            return got
        assert time.monotonic() < deadline, f"never got {what}"
        await asyncio.sleep(0.05)  # pacing between questions, not a bound


async def test_completion_offers_the_objects_a_running_adapter_has_now(client: LanguageClient, project):
    text = LAYOUT + "let any = root.vehicles.\n"
    uri = open_layout(client, project / "hud.mocu", text)
    await diagnostics_of(client, uri, 1)
    line = len(text.splitlines()) - 1
    col = len("let any = root.vehicles.")

    async def live_ones():
        labels = await completion_labels(client, uri, line, col)
        return labels if {"ugv1", "uav1"} <= set(labels) else None

    labels = await until("the UGV and the UAV among the completions", live_ones)
    assert set(VEHICLES) <= set(labels)
    assert labels["ugv1"].detail == "live (not in the schemas)"


async def test_completion_of_a_property_shows_its_current_value(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    await diagnostics_of(client, uri, 1)
    line = 2
    col = LAYOUT.splitlines()[line].index("sped")

    async def with_value():
        labels = await completion_labels(client, uri, line, col)
        speed = labels.get("speed")
        return speed if speed is not None and "now " in speed.detail else None

    speed = await until("the speed's current value in its completion", with_value)
    assert speed.detail.startswith("number (m/s)") and " · now " in speed.detail, speed.detail
    labels = await completion_labels(client, uri, line, col)
    assert "write_at_owner" not in labels, "the mirror's plumbing for `set` is not offered"


async def test_hover_shows_the_current_value_its_units_and_age(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    await diagnostics_of(client, uri, 1)
    line = 5
    col = LAYOUT.splitlines()[line].index("speed  label") + 1

    async def live_hover():
        h = await client.text_document_hover_async(types.HoverParams(**at(uri, line, col)))
        # The value may be mirrored a moment before its units (the adapter's object record).
        return h if h is not None and " m/s` (on " in h.contents.value else None

    h = await until("the speed's current value with its units in its hover", live_hover)
    value = h.contents.value
    assert "Speed over ground" in value, "what the schema says stays"
    assert " m/s` (on tcp/127.0.0.1:" in value and " s ago)" in value, value
