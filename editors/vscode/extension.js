// Starts `xabsl lsp` (stdio) for .xabsl documents through vscode-languageclient.
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const config = vscode.workspace.getConfiguration("xabsl");
  const [command, ...args] = config.get("server.command", ["xabsl", "lsp"]);
  const agents = config.get("agents", null);
  client = new LanguageClient(
    "xabsl",
    "XABSL language server",
    { command, args },
    {
      documentSelector: [{ scheme: "file", language: "xabsl" }],
      initializationOptions: agents ? { agents } : undefined,
      synchronize: { fileEvents: vscode.workspace.createFileSystemWatcher("**/*.xabsl") },
    },
  );
  context.subscriptions.push({ dispose: () => client && client.stop() });
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
