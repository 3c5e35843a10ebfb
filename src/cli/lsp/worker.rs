//! The diagnostics thread: checks the documents that changed, a debounce after the last
//! change, on a snapshot of the open buffers; a newer change cancels the check in flight, and
//! only the diagnostics of a document's latest version are published.

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Sender;
use lsp_server::{Message, Notification};
use lsp_types::Uri;
use sppm_lang::Cancel;
use sppm_lang::internals::ide::{self, CheckLimits};
use sppm_lang::internals::world::{FileSystem, Overlay, SharedWorld};

/// How long the text must stay unchanged before it is checked.
pub const DEBOUNCE: Duration = Duration::from_millis(200);
/// The longest one check may run (a huge scene's prepare stage): then it is stopped and says so.
pub const TIME_LIMIT: Duration = Duration::from_secs(5);

/// An open document as the worker sees it.
#[derive(Clone)]
pub struct Open {
    pub uri: Uri,
    pub version: i32,
    pub text: Arc<str>,
}

/// The global names and values a document's last evaluation left, sorted by name.
pub type Globals = Arc<Vec<(String, String)>>;

/// What the editor thread shares with the worker.
#[derive(Default)]
pub struct Shared {
    state: Mutex<State>,
    wake: Condvar,
    /// The last evaluation's global names and values, per document (for hover).
    pub globals: Mutex<HashMap<PathBuf, Globals>>,
}

#[derive(Default)]
struct State {
    /// The open documents, by path.
    open: HashMap<PathBuf, Open>,
    /// Documents to check.
    dirty: BTreeSet<PathBuf>,
    last_change: Option<Instant>,
    /// The check in flight: its document and cancel handle. Taken (and the document marked
    /// dirty again) by a change that cancels it.
    running: Option<(PathBuf, Cancel)>,
    /// What each document's last check read.
    dependencies: HashMap<PathBuf, Vec<PathBuf>>,
    stop: bool,
}

impl Shared {
    /// A document was opened or changed: it (and the open documents that read it) are checked
    /// after the debounce; a check in flight is cancelled.
    pub fn changed(&self, path: PathBuf, doc: Open) {
        let mut s = lock(&self.state);
        let readers: Vec<PathBuf> = s
            .dependencies
            .iter()
            .filter(|(p, deps)| **p != path && deps.contains(&path) && s.open.contains_key(*p))
            .map(|(p, _)| p.clone())
            .collect();
        s.dirty.extend(readers);
        s.dirty.insert(path.clone());
        s.open.insert(path, doc);
        s.last_change = Some(Instant::now());
        // The check in flight read the old text (or another document's): it starts again.
        if let Some((p, c)) = s.running.take() {
            c.cancel();
            s.dirty.insert(p);
        }
        self.wake.notify_all();
    }

    pub fn closed(&self, path: &Path) {
        let mut s = lock(&self.state);
        s.open.remove(path);
        s.dirty.remove(path);
        s.dependencies.remove(path);
        lock(&self.globals).remove(path);
    }

    pub fn stop(&self) {
        let mut s = lock(&self.state);
        s.stop = true;
        if let Some((_, c)) = s.running.take() {
            c.cancel();
        }
        self.wake.notify_all();
    }

    /// The checks the worker runs until [`Shared::stop`].
    pub fn run(&self, sender: &Sender<Message>, limits: &CheckLimits) {
        loop {
            let (path, doc, files, cancel) = {
                let mut s = lock(&self.state);
                loop {
                    if s.stop {
                        return;
                    }
                    let quiet = s.last_change.map_or(DEBOUNCE, |t| t.elapsed());
                    if !s.dirty.is_empty() && quiet >= DEBOUNCE {
                        break;
                    }
                    let wait = if s.dirty.is_empty() {
                        Duration::from_secs(3600)
                    } else {
                        DEBOUNCE - quiet
                    };
                    s = self
                        .wake
                        .wait_timeout(s, wait)
                        .unwrap_or_else(|e| e.into_inner())
                        .0;
                }
                let path = s.dirty.pop_first().expect("a dirty document");
                let Some(doc) = s.open.get(&path).cloned() else {
                    continue;
                };
                let files: Vec<(PathBuf, Arc<str>)> = s
                    .open
                    .iter()
                    .map(|(p, d)| (p.clone(), d.text.clone()))
                    .collect();
                let cancel = Cancel::new();
                s.running = Some((path.clone(), cancel.clone()));
                (path, doc, files, cancel)
            };
            let mut world = Overlay::new(FileSystem);
            for (p, text) in files {
                world.insert_shared(p, Arc::<[u8]>::from(text));
            }
            let checked = with_time_limit(&cancel, || {
                ide::check(&path, SharedWorld::new(world), cancel.clone(), limits)
            });
            let mut s = lock(&self.state);
            // A change cancelled it (and queued it again), or the server is stopping.
            let superseded = s.running.take().is_none();
            let current = s.open.get(&path).map(|d| d.version);
            if superseded || current != Some(doc.version) {
                continue;
            }
            let mut diagnostics = checked.diagnostics;
            if checked.interrupted {
                diagnostics.push(ide::FileDiagnostic {
                    start: ide::Position::default(),
                    end: ide::Position::default(),
                    severity: sppm_lang::Severity::Warning,
                    message: format!(
                        "the check was stopped after {} s; run `sppm-lang check` for its \
                         diagnostics",
                        TIME_LIMIT.as_secs()
                    ),
                });
            }
            s.dependencies.insert(path.clone(), checked.dependencies);
            lock(&self.globals).insert(path, Arc::new(checked.globals));
            // Sent under the lock: a close or a newer version cannot come in between.
            publish(sender, &doc.uri, Some(doc.version), &diagnostics);
        }
    }
}

/// Runs `work`, raising `cancel` if it has not returned within [`TIME_LIMIT`].
fn with_time_limit<T>(cancel: &Cancel, work: impl FnOnce() -> T) -> T {
    let (done, finished) = std::sync::mpsc::channel::<()>();
    let c = cancel.clone();
    let watchdog = std::thread::Builder::new()
        .name("lsp-watchdog".into())
        .spawn(move || {
            if let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                finished.recv_timeout(TIME_LIMIT)
            {
                c.cancel();
            }
        });
    let out = work();
    drop(done);
    if let Ok(w) = watchdog {
        let _ = w.join();
    }
    out
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Sends a document's diagnostics.
pub fn publish(
    sender: &Sender<Message>,
    uri: &Uri,
    version: Option<i32>,
    diagnostics: &[ide::FileDiagnostic],
) {
    let params = lsp_types::PublishDiagnosticsParams {
        uri: uri.clone(),
        version,
        diagnostics: diagnostics.iter().map(super::convert::diagnostic).collect(),
    };
    let n = Notification::new("textDocument/publishDiagnostics".into(), params);
    let _ = sender.send(n.into());
}
