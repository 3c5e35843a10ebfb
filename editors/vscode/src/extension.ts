// Starts `sppm-lang lsp` over stdio for `.scn` files; highlighting comes from the TextMate
// grammar (syntaxes/scn.tmLanguage.json), which works without the server.
import * as vscode from "vscode";
import {
  LanguageClient,
  LanguageClientOptions,
  ServerOptions,
  TransportKind,
} from "vscode-languageclient/node";

let client: LanguageClient | undefined;

function serverPath(): string {
  const configured = vscode.workspace.getConfiguration("sppm-lang").get<string>("serverPath");
  return configured && configured.trim() !== "" ? configured.trim() : "sppm-lang";
}

async function start(): Promise<void> {
  const command = serverPath();
  const run = { command, args: ["lsp"], transport: TransportKind.stdio };
  const serverOptions: ServerOptions = { run, debug: run };
  const clientOptions: LanguageClientOptions = {
    documentSelector: [{ language: "scn" }],
    synchronize: {
      // Included files and textures change what a scene means: tell the server when they do.
      fileEvents: vscode.workspace.createFileSystemWatcher("**/*.{scn,obj,png,jpg,jpeg,hdr,exr}"),
    },
  };
  client = new LanguageClient("sppm-lang", "sppm-lang", serverOptions, clientOptions);
  try {
    await client.start();
  } catch (err) {
    // A missing program is the usual cause: say which one was tried and where to change it.
    client = undefined;
    const message = err instanceof Error ? err.message : String(err);
    void vscode.window.showErrorMessage(
      `sppm-lang: could not start "${command} lsp" (${message}). ` +
        `Install sppm-lang or set "sppm-lang.serverPath".`,
    );
  }
}

async function restart(): Promise<void> {
  const old = client;
  client = undefined;
  if (old) {
    await old.stop();
  }
  await start();
}

export async function activate(context: vscode.ExtensionContext): Promise<void> {
  context.subscriptions.push(
    { dispose: () => void client?.stop() },
    vscode.commands.registerCommand("sppm-lang.restartServer", () => restart()),
    vscode.workspace.onDidChangeConfiguration((e) => {
      if (e.affectsConfiguration("sppm-lang.serverPath")) {
        void restart();
      }
    }),
  );
  await start();
}

export async function deactivate(): Promise<void> {
  const old = client;
  client = undefined;
  if (old) {
    await old.stop();
  }
}
