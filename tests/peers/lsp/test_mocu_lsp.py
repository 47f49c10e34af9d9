"""`mocu lsp` end to end, driven by a real LSP client (pytest-lsp, pinned in .ci/run).

Run by tests/cli_lsp.rs with MOCU_BIN set to the built `mocu`; each test starts the server
on a fresh project (a profile, a schema and a layout in a temporary folder) and talks to it
over stdio as an editor would: open, edit, diagnostics, completion (of `use` paths too),
hover, definition, references, rename, symbols, semantic tokens, code actions, formatting of
a document and of a range.
"""

import json
import os
import pathlib
import subprocess

import pytest
import pytest_lsp
from lsprotocol import types
from pytest_lsp import ClientServerConfig, LanguageClient

MOCU = os.environ["MOCU_BIN"]

PROFILE = """[profile]
name = "lsp-test"
layouts = ["hud.mocu"]
schemas = ["vehicles.toml"]
"""

SCHEMA = """[[instances]]
path = "root.vehicles.usv*"
type = "usv"

[types.usv]
description = "Unmanned surface vehicle"
children = { nav = "nav" }
[types.usv.properties]
fuel = { type = "float", range = [0, 1], read_only = true, description = "Fuel left, 0 to 1" }
[types.usv.methods]
stop = { description = "Stop at once" }

[types.nav.properties]
speed = { type = "float", units = "m/s", description = "Speed over ground" }
heading = { type = "float", units = "deg", description = "Heading" }
"""

# The layout under test: line numbers below are 0-based, as LSP counts them.
LAYOUT = """use "stdlib/gauges.mocu"
let usv = root.vehicles.usv1
let fast = usv.nav.sped > 5
window hud { layer 1  rect 0 0 100% 100% }
in hud {
  speed: Dial { at 10 10 100 100  value usv.nav.speed  label "SPD" }
}
watch slow {
  when fast for 2s
  then show hud
}
bind gamepad {
  button south -> call usv.stop()
}
"""


@pytest.fixture
def project(tmp_path: pathlib.Path) -> pathlib.Path:
    (tmp_path / "project.toml").write_text(PROFILE)
    (tmp_path / "vehicles.toml").write_text(SCHEMA)
    (tmp_path / "hud.mocu").write_text(LAYOUT)
    return tmp_path


@pytest_lsp.fixture(config=ClientServerConfig(server_command=[MOCU, "lsp"]))
async def client(lsp_client: LanguageClient):
    await lsp_client.initialize_session(
        types.InitializeParams(capabilities=types.ClientCapabilities())
    )
    yield
    await lsp_client.shutdown_session()


async def diagnostics_of(client: LanguageClient, uri: str, version: int):
    """Waits until the server has published the diagnostics of `uri` at `version`."""
    while True:
        got = client.diagnostics.get(uri)
        if got is not None and client_versions.get(uri) == version:
            return got
        params = await client.wait_for_notification(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        if params.uri == uri and params.version is not None:
            client_versions[uri] = params.version


client_versions: dict = {}


def open_layout(client: LanguageClient, path: pathlib.Path, text: str | None = None) -> str:
    uri = path.as_uri()
    client_versions.pop(uri, None)
    client.text_document_did_open(
        types.DidOpenTextDocumentParams(
            text_document=types.TextDocumentItem(
                uri=uri, language_id="mocu", version=1, text=text or path.read_text()
            )
        )
    )
    return uri


def at(uri: str, line: int, character: int) -> dict:
    """The document and position arguments of a positional request."""
    return dict(
        text_document=types.TextDocumentIdentifier(uri=uri),
        position=types.Position(line=line, character=character),
    )


async def completion_labels(client: LanguageClient, uri: str, line: int, character: int) -> dict:
    items = await client.text_document_completion_async(types.CompletionParams(**at(uri, line, character)))
    items = items if isinstance(items, list) else items.items
    return {i.label: i for i in items}


def line_col(line: int, word: str) -> tuple[int, int]:
    return line, LAYOUT.splitlines()[line].index(word)


async def test_diagnostics_on_open_are_those_of_mocu_check(client: LanguageClient, project):
    hud = project / "hud.mocu"
    uri = open_layout(client, hud)
    got = await diagnostics_of(client, uri, 1)
    cli = subprocess.run(
        [MOCU, "check", "--format", "json", str(hud)], capture_output=True, text=True
    )
    expected = json.loads(cli.stdout)
    assert expected, "the layout has a finding for both to report"
    assert [d["code"] for d in expected] == [d.code for d in got]
    for e, d in zip(expected, got):
        assert (d.range.start.line, d.range.start.character) == (e["line"] - 1, e["column"] - 1)
        assert (d.range.end.line, d.range.end.character) == (e["end_line"] - 1, e["end_column"] - 1)
        assert d.message.startswith(e["message"])
        if "help" in e:
            assert d.message.endswith("help: " + e["help"])
    assert got[0].code == "E0301" or "sped" in got[0].message


async def test_an_edit_republishes_the_diagnostics_of_the_new_text(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    assert await diagnostics_of(client, uri, 1)
    line, start = line_col(2, "sped")
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            text_document=types.VersionedTextDocumentIdentifier(uri=uri, version=2),
            content_changes=[
                types.TextDocumentContentChangePartial(
                    range=types.Range(
                        start=types.Position(line=line, character=start),
                        end=types.Position(line=line, character=start + 4),
                    ),
                    text="speed",
                )
            ],
        )
    )
    assert list(await diagnostics_of(client, uri, 2)) == []


async def test_an_unsaved_error_is_reported_before_the_file_is_saved(client: LanguageClient, project):
    broken = LAYOUT.replace("label \"SPD\"", "lable \"SPD\"")
    uri = open_layout(client, project / "hud.mocu", broken)
    got = await diagnostics_of(client, uri, 1)
    assert any("lable" in d.message and "did you mean `label`" in d.message for d in got)


async def test_completion_after_a_dot_offers_the_schema_members_with_units(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    await diagnostics_of(client, uri, 1)
    line, c = line_col(2, "sped")
    labels = await completion_labels(client, uri, line, c)
    assert "speed" in labels and "m/s" in labels["speed"].detail
    assert "heading" in labels


async def test_completion_inside_a_widget_offers_its_parameters(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    await diagnostics_of(client, uri, 1)
    line, c = line_col(5, "label")
    labels = await completion_labels(client, uri, line, c)
    assert "units" in labels and "string" in labels["units"].detail
    assert "value" not in labels, "a parameter already written is not offered again"
    assert "Dial" in labels and "let" in labels and "usv" in labels


async def test_completion_in_a_binding_offers_the_devices_inputs(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(12, "south")
    labels = await completion_labels(client, uri, line, c)
    assert {"south", "east", "left_bumper"} <= set(labels)
    assert labels["south"].detail == "gamepad button"


async def test_hover_shows_a_components_documentation(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(5, "Dial")
    h = await client.text_document_hover_async(types.HoverParams(**(at(uri, line, c + 1))))
    assert "### Dial" in h.contents.value and "| `range` |" in h.contents.value


async def test_hover_on_a_path_shows_its_schema_type_and_units(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    await diagnostics_of(client, uri, 1)
    line, c = line_col(5, "speed  label")
    h = await client.text_document_hover_async(types.HoverParams(**(at(uri, line, c + 1))))
    assert "root.vehicles.usv1.nav.speed" in h.contents.value
    assert "m/s" in h.contents.value and "Speed over ground" in h.contents.value


async def test_hover_on_a_let_shows_its_checked_type(client: LanguageClient, project):
    fixed = LAYOUT.replace("sped", "speed")
    uri = open_layout(client, project / "hud.mocu", fixed)
    await diagnostics_of(client, uri, 1)
    line, c = line_col(8, "fast")
    h = await client.text_document_hover_async(types.HoverParams(**(at(uri, line, c))))
    assert "let fast" in h.contents.value and "type: bool" in h.contents.value


async def test_definition_of_a_component_is_in_the_used_stdlib_file(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(5, "Dial")
    loc = await client.text_document_definition_async(types.DefinitionParams(**(at(uri, line, c))))
    assert loc.uri.endswith("/stdlib/gauges.mocu")
    text = pathlib.Path(loc.uri.removeprefix("file://")).read_text().splitlines()[loc.range.start.line]
    assert text[loc.range.start.character:].startswith("Dial")


async def test_definition_of_a_let_and_of_a_window(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(8, "fast")
    loc = await client.text_document_definition_async(types.DefinitionParams(**(at(uri, line, c))))
    assert (loc.range.start.line, loc.range.start.character) == line_col(2, "fast")
    line, c = line_col(9, "hud")
    loc = await client.text_document_definition_async(types.DefinitionParams(**(at(uri, line, c))))
    assert (loc.range.start.line, loc.range.start.character) == line_col(3, "hud")


async def test_references_list_every_use_of_a_let(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(1, "usv")
    refs = await client.text_document_references_async(
        types.ReferenceParams(**(at(uri, line, c)), context=types.ReferenceContext(include_declaration=True))
    )
    assert sorted(r.range.start.line for r in refs) == [1, 2, 5, 12]


async def test_rename_of_a_window_edits_its_definition_and_every_use(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(3, "hud")
    edit = await client.text_document_rename_async(
        types.RenameParams(**(at(uri, line, c)), new_name="overlay")
    )
    edits = edit.changes[uri]
    assert sorted(e.range.start.line for e in edits) == [3, 4, 9]
    assert all(e.new_text == "overlay" for e in edits)


async def test_rename_refuses_a_keyword(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    line, c = line_col(1, "usv")
    with pytest.raises(Exception, match="not a name"):
        await client.text_document_rename_async(types.RenameParams(**(at(uri, line, c)), new_name="window"))


async def test_document_symbols_outline_lets_windows_widgets_and_watches(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    syms = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=types.TextDocumentIdentifier(uri=uri))
    )
    names = [s.name for s in syms]
    assert names == ['use "stdlib/gauges.mocu"', "usv", "fast", "hud", "in hud", "slow", "bind gamepad"]
    assert [w.name for w in syms[4].children] == ["speed"]


async def test_semantic_tokens_mark_keywords_components_and_lets(client: LanguageClient, project):
    uri = open_layout(client, project / "hud.mocu")
    res = await client.text_document_semantic_tokens_full_async(
        types.SemanticTokensParams(text_document=types.TextDocumentIdentifier(uri=uri))
    )
    data = res.data
    assert len(data) % 5 == 0 and len(data) > 20
    # The first token is the `use` keyword at 0:0 (type 0, keyword).
    assert list(data[:5]) == [0, 0, 3, 0, 0]


async def test_a_did_you_mean_diagnostic_has_a_quick_fix(client: LanguageClient, project):
    broken = LAYOUT.replace("label \"SPD\"", "lable \"SPD\"")
    uri = open_layout(client, project / "hud.mocu", broken)
    diags = await diagnostics_of(client, uri, 1)
    fixable = [d for d in diags if "did you mean `label`" in d.message]
    actions = await client.text_document_code_action_async(
        types.CodeActionParams(
            text_document=types.TextDocumentIdentifier(uri=uri),
            range=fixable[0].range,
            context=types.CodeActionContext(diagnostics=fixable),
        )
    )
    edit = actions[0].edit.changes[uri][0]
    assert edit.new_text == "label"
    line = broken.splitlines()[edit.range.start.line]
    assert line[edit.range.start.character:edit.range.end.character] == "lable"


async def format_edits(client: LanguageClient, uri: str):
    return await client.text_document_formatting_async(
        types.DocumentFormattingParams(
            text_document=types.TextDocumentIdentifier(uri=uri),
            options=types.FormattingOptions(tab_size=2, insert_spaces=True),
        )
    )


async def test_formatting_gives_mocu_fmts_canonical_text_and_nothing_once_formatted(client: LanguageClient, project):
    messy = "let   a =    1\nwindow w {layer a   rect 0 0 10 10}\n"
    uri = open_layout(client, project / "messy.mocu", messy)
    edits = await format_edits(client, uri)
    assert len(edits) == 1 and edits[0].range.start == types.Position(line=0, character=0)
    formatted = edits[0].new_text
    assert formatted != messy and formatted.startswith("let a = 1\n")
    again = open_layout(client, project / "formatted.mocu", formatted)
    assert list(await format_edits(client, again)) == []


async def test_range_formatting_formats_only_the_items_the_range_touches(client: LanguageClient, project):
    messy = "let   a =    1\nwindow w {layer a   rect 0 0 10 10}\nlet  b  =  a+1\n"
    uri = open_layout(client, project / "messy.mocu", messy)
    edits = await client.text_document_range_formatting_async(
        types.DocumentRangeFormattingParams(
            text_document=types.TextDocumentIdentifier(uri=uri),
            range=types.Range(start=types.Position(line=1, character=12), end=types.Position(line=1, character=14)),
            options=types.FormattingOptions(tab_size=2, insert_spaces=True),
        )
    )
    assert len(edits) == 1
    e = edits[0]
    assert (e.range.start, e.range.end) == (types.Position(line=1, character=0), types.Position(line=1, character=35))
    whole = (await format_edits(client, uri))[0].new_text
    assert e.new_text.startswith("window w {") and e.new_text in whole
    assert "layer a   rect" not in e.new_text


async def test_completion_inside_a_use_offers_the_folders_layouts_and_the_stdlibs(client: LanguageClient, project):
    (project / "common.mocu").write_text(COMMON)
    uri = open_layout(client, project / "paths.mocu", 'use "\nuse "stdlib/\n')
    top = await completion_labels(client, uri, 0, 5)
    assert {"common.mocu", "hud.mocu", "stdlib/"} <= set(top) and "paths.mocu" not in top
    assert top["stdlib/"].kind == types.CompletionItemKind.Folder
    lib = await completion_labels(client, uri, 1, 12)
    assert "gauges.mocu" in lib
    edit = lib["gauges.mocu"].text_edit
    assert (edit.range.start.character, edit.range.end.character) == (12, 12)


async def test_formatting_leaves_a_file_with_syntax_errors_alone(client: LanguageClient, project):
    uri = open_layout(client, project / "broken.mocu", "let a = (1 +\n")
    assert list(await format_edits(client, uri)) == []


COMMON = """let limit = 5
window alerts { layer 9  rect 0 0 10% 10% }
"""

USER = """use "common.mocu" as c
use "common.mocu"
let over = c.limit > 3
watch w { when over then show alerts }
"""


async def test_definition_rename_and_references_reach_across_use_files(client: LanguageClient, project):
    (project / "common.mocu").write_text(COMMON)
    user = open_layout(client, project / "user.mocu", USER)
    common = open_layout(client, project / "common.mocu")
    # `c.limit` → the let in common.mocu; `alerts` → the window there.
    loc = await client.text_document_definition_async(types.DefinitionParams(**at(user, 2, USER.splitlines()[2].index("limit"))))
    assert loc.uri == common and (loc.range.start.line, loc.range.start.character) == (0, 4)
    loc = await client.text_document_definition_async(types.DefinitionParams(**at(user, 3, USER.splitlines()[3].index("alerts"))))
    assert loc.uri == common and loc.range.start.line == 1
    # Renaming the let where it is defined edits its use in the other open document.
    edit = await client.text_document_rename_async(types.RenameParams(**at(common, 0, 4), new_name="ceiling"))
    assert sorted(edit.changes) == sorted([common, user])
    assert [e.range.start.line for e in edit.changes[user]] == [2]
    refs = await client.text_document_references_async(
        types.ReferenceParams(**at(common, 1, 7), context=types.ReferenceContext(include_declaration=False))
    )
    assert [(r.uri, r.range.start.line) for r in refs] == [(user, 3)]
