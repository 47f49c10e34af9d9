// The Mocu extension: starts `mocu lsp` (stdio) for .mocu files. Everything the editor
// shows beyond highlighting comes from the server: docs/editors.md.
"use strict";

const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const config = vscode.workspace.getConfiguration("mocu");
  const command = config.get("server.path") || "mocu";
  const server = { command, args: ["lsp"] };
  client = new LanguageClient(
    "mocu",
    "Mocu language server",
    { run: server, debug: server },
    {
      documentSelector: [{ scheme: "file", language: "mocu" }],
      // Live values in completion and hover from a running OCU or adapter (docs/editors.md).
      initializationOptions: { live: { connect: config.get("live.connect") || [] } },
      // Profiles and schemas change what a layout means: tell the server when they are saved.
      synchronize: {
        fileEvents: vscode.workspace.createFileSystemWatcher("**/*.{mocu,toml}"),
      },
    }
  );
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
