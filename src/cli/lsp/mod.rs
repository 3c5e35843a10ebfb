//! `sppm-lang lsp`: a Language Server Protocol server over stdin and stdout. A thin loop over
//! the library's editor support (`sppm_lang::internals::ide`): it keeps the open documents, answers
//! requests on this thread (completion, hover, definition, references, symbols: each reads
//! the text only) and leaves diagnostics, which evaluate the scene, to a worker thread.

mod convert;
mod transport;
mod worker;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types as lsp;
use sppm_lang::internals::ide::{self, LineIndex, Outline};
use sppm_lang::internals::world::{FileSystem, Overlay};

use worker::{Open, Shared};

/// A document's line index and outline, made from one version of its text.
type Analysis = Arc<(LineIndex, Outline)>;

/// Where a request's cursor stands: the document, its analysis and the byte offset.
struct Cursor {
    path: PathBuf,
    text: Arc<str>,
    analysis: Analysis,
    offset: usize,
}

/// An open document.
struct Doc {
    uri: lsp::Uri,
    text: Arc<str>,
    /// Made when a request first needs it after a change.
    analysis: Option<Analysis>,
}

struct Server {
    sender: crossbeam_channel::Sender<Message>,
    docs: HashMap<PathBuf, Doc>,
    shared: Arc<Shared>,
    shut_down: bool,
}

pub fn run() -> ExitCode {
    let (connection, io) = transport::stdio();
    let code = serve(&connection);
    drop(connection);
    io.join();
    code
}

fn capabilities() -> lsp::ServerCapabilities {
    lsp::ServerCapabilities {
        text_document_sync: Some(lsp::TextDocumentSyncCapability::Kind(
            lsp::TextDocumentSyncKind::INCREMENTAL,
        )),
        completion_provider: Some(lsp::CompletionOptions {
            trigger_characters: Some(vec!["#".into(), "\"".into(), "/".into()]),
            ..Default::default()
        }),
        hover_provider: Some(lsp::HoverProviderCapability::Simple(true)),
        definition_provider: Some(lsp::OneOf::Left(true)),
        references_provider: Some(lsp::OneOf::Left(true)),
        document_symbol_provider: Some(lsp::OneOf::Left(true)),
        ..Default::default()
    }
}

/// The session: the handshake, then messages until `exit` (or the input ends).
fn serve(connection: &Connection) -> ExitCode {
    let init = serde_json::json!({
        "capabilities": capabilities(),
        "serverInfo": { "name": "sppm-lang", "version": env!("CARGO_PKG_VERSION") },
    });
    // The handshake: requests before `initialize` are refused, notifications ignored
    // (`initialized` among them, after it), `exit` ends the session.
    loop {
        match connection.receiver.recv() {
            Ok(Message::Request(r)) if r.method == "initialize" => {
                let _ = connection.sender.send(Response::new_ok(r.id, init).into());
                break;
            }
            Ok(Message::Request(r)) => {
                let refusal = Response::new_err(
                    r.id,
                    ErrorCode::ServerNotInitialized as i32,
                    "the first request must be `initialize`".into(),
                );
                let _ = connection.sender.send(refusal.into());
            }
            Ok(Message::Notification(n)) if n.method == "exit" => return ExitCode::from(1),
            Ok(_) => {}
            Err(_) => return ExitCode::from(1),
        }
    }
    let shared = Arc::new(Shared::default());
    let worker = {
        let (shared, sender) = (shared.clone(), connection.sender.clone());
        std::thread::Builder::new()
            .name("lsp-diagnostics".into())
            .spawn(move || shared.run(&sender, &ide::CheckLimits::default()))
    };
    let mut server = Server {
        sender: connection.sender.clone(),
        docs: HashMap::new(),
        shared: shared.clone(),
        shut_down: false,
    };
    let mut code = ExitCode::from(1);
    for message in &connection.receiver {
        match message {
            Message::Request(r) => server.request(r),
            Message::Notification(n) if n.method == "exit" => {
                if server.shut_down {
                    code = ExitCode::SUCCESS;
                }
                break;
            }
            Message::Notification(n) => server.notification(n),
            Message::Response(_) => {}
        }
    }
    shared.stop();
    if let Ok(w) = worker {
        let _ = w.join();
    }
    code
}

impl Server {
    fn reply(&self, r: Response) {
        let _ = self.sender.send(r.into());
    }

    fn request(&mut self, r: Request) {
        let id = r.id.clone();
        if self.shut_down {
            return self.reply(Response::new_err(
                id,
                ErrorCode::InvalidRequest as i32,
                "the server is shut down".into(),
            ));
        }
        let result = match r.method.as_str() {
            "shutdown" => {
                self.shut_down = true;
                self.shared.stop();
                Ok(serde_json::Value::Null)
            }
            "textDocument/completion" => self.with_params(r.params, Server::completion),
            "textDocument/hover" => self.with_params(r.params, Server::hover),
            "textDocument/definition" => self.with_params(r.params, Server::definition),
            "textDocument/references" => self.with_params(r.params, Server::references),
            "textDocument/documentSymbol" => self.with_params(r.params, Server::symbols),
            other => Err((ErrorCode::MethodNotFound, format!("no method `{other}`"))),
        };
        self.reply(match result {
            Ok(v) => Response::new_ok(id, v),
            Err((code, message)) => Response::new_err(id, code as i32, message),
        });
    }

    fn with_params<P: serde::de::DeserializeOwned, R: serde::Serialize>(
        &mut self,
        params: serde_json::Value,
        handler: fn(&mut Server, P) -> Option<R>,
    ) -> Result<serde_json::Value, (ErrorCode, String)> {
        let p: P = serde_json::from_value(params)
            .map_err(|e| (ErrorCode::InvalidParams, format!("invalid parameters: {e}")))?;
        Ok(handler(self, p).map_or(serde_json::Value::Null, |r| {
            serde_json::to_value(r).unwrap_or(serde_json::Value::Null)
        }))
    }

    fn notification(&mut self, n: Notification) {
        match n.method.as_str() {
            "textDocument/didOpen" => {
                if let Ok(p) = serde_json::from_value::<lsp::DidOpenTextDocumentParams>(n.params) {
                    let d = p.text_document;
                    self.set(d.uri, d.version, d.text.into());
                }
            }
            "textDocument/didChange" => {
                if let Ok(p) = serde_json::from_value::<lsp::DidChangeTextDocumentParams>(n.params)
                {
                    self.change(p);
                }
            }
            "textDocument/didClose" => {
                if let Ok(p) = serde_json::from_value::<lsp::DidCloseTextDocumentParams>(n.params) {
                    let path = convert::path(&p.text_document.uri);
                    self.docs.remove(&path);
                    self.shared.closed(&path);
                    worker::publish(&self.sender, &p.text_document.uri, None, &[]);
                }
            }
            // `initialized`, `$/cancelRequest` (every answer is immediate), saves, settings.
            _ => {}
        }
    }

    fn set(&mut self, uri: lsp::Uri, version: i32, text: Arc<str>) {
        let path = convert::path(&uri);
        self.shared.changed(
            path.clone(),
            Open {
                uri: uri.clone(),
                version,
                text: text.clone(),
            },
        );
        self.docs.insert(
            path,
            Doc {
                uri,
                text,
                analysis: None,
            },
        );
    }

    /// Applies the changes in order (a range replaced, or the whole text).
    fn change(&mut self, p: lsp::DidChangeTextDocumentParams) {
        let path = convert::path(&p.text_document.uri);
        let Some(doc) = self.docs.get(&path) else {
            return;
        };
        let mut text = doc.text.to_string();
        for c in p.content_changes {
            match c.range {
                Some(r) => {
                    let index = LineIndex::new(&text);
                    let a = index.offset(&text, convert::from_position(r.start));
                    let b = index.offset(&text, convert::from_position(r.end));
                    text.replace_range(a.min(b)..b.max(a), &c.text);
                }
                None => text = c.text,
            }
        }
        let uri = doc.uri.clone();
        self.set(uri, p.text_document.version, text.into());
    }

    /// The document, its line index and outline.
    fn doc(&mut self, uri: &lsp::Uri) -> Option<(PathBuf, Arc<str>, Analysis)> {
        let path = convert::path(uri);
        let doc = self.docs.get_mut(&path)?;
        let text = doc.text.clone();
        let a = doc
            .analysis
            .get_or_insert_with(|| Arc::new((LineIndex::new(&text), Outline::new(&text))))
            .clone();
        Some((path, text, a))
    }

    /// The open documents over the disk: what the includes are read from.
    fn world(&self) -> Overlay<FileSystem> {
        let mut w = Overlay::new(FileSystem);
        for (p, d) in &self.docs {
            w.insert_shared(p, Arc::<[u8]>::from(d.text.clone()));
        }
        w
    }

    fn globals(&self, path: &Path) -> worker::Globals {
        self.shared
            .globals
            .lock()
            .ok()
            .and_then(|g| g.get(path).cloned())
            .unwrap_or_default()
    }

    /// The document and offset a request's cursor points at.
    fn cursor(&mut self, at: &lsp::TextDocumentPositionParams) -> Option<Cursor> {
        let (path, text, analysis) = self.doc(&at.text_document.uri)?;
        let offset = analysis
            .0
            .offset(&text, convert::from_position(at.position));
        Some(Cursor {
            path,
            text,
            analysis,
            offset,
        })
    }

    fn completion(&mut self, p: lsp::CompletionParams) -> Option<lsp::CompletionResponse> {
        let c = self.cursor(&p.text_document_position)?;
        let (index, outline) = &*c.analysis;
        let globals = self.globals(&c.path);
        let found = ide::complete(&self.world(), &c.path, &c.text, outline, c.offset, &globals);
        let replace = convert::range(&c.text, index, found.replace.clone());
        Some(lsp::CompletionResponse::Array(
            found
                .items
                .iter()
                .enumerate()
                .map(|(k, i)| convert::completion(i, k, replace))
                .collect(),
        ))
    }

    fn hover(&mut self, p: lsp::HoverParams) -> Option<lsp::Hover> {
        let c = self.cursor(&p.text_document_position_params)?;
        let (index, outline) = &*c.analysis;
        let globals = self.globals(&c.path);
        let h = ide::hover(&self.world(), &c.path, &c.text, outline, c.offset, &globals)?;
        Some(lsp::Hover {
            contents: lsp::HoverContents::Markup(lsp::MarkupContent {
                kind: lsp::MarkupKind::Markdown,
                value: h.text,
            }),
            range: Some(convert::range(&c.text, index, h.range)),
        })
    }

    fn definition(&mut self, p: lsp::GotoDefinitionParams) -> Option<lsp::GotoDefinitionResponse> {
        let c = self.cursor(&p.text_document_position_params)?;
        let found = ide::definition(&self.world(), &c.path, &c.text, &c.analysis.1, c.offset);
        Some(lsp::GotoDefinitionResponse::Array(
            found.iter().filter_map(convert::location).collect(),
        ))
    }

    fn references(&mut self, p: lsp::ReferenceParams) -> Option<Vec<lsp::Location>> {
        let c = self.cursor(&p.text_document_position)?;
        let declaration = p.context.include_declaration;
        let found = ide::references(
            &self.world(),
            &c.path,
            &c.text,
            &c.analysis.1,
            c.offset,
            declaration,
        );
        Some(found.iter().filter_map(convert::location).collect())
    }

    fn symbols(&mut self, p: lsp::DocumentSymbolParams) -> Option<lsp::DocumentSymbolResponse> {
        let (_, text, a) = self.doc(&p.text_document.uri)?;
        let (index, outline) = &*a;
        let symbols = ide::symbols(&text, outline);
        Some(lsp::DocumentSymbolResponse::Nested(
            symbols
                .iter()
                .map(|s| convert::symbol(&text, index, s))
                .collect(),
        ))
    }
}
