//! `sppm-lang lsp` driven as an editor drives it: the real binary over stdin and stdout, with
//! JSON-RPC messages framed by `Content-Length` headers. A session on the examples and on
//! broken files (every `tests/bad` case, a half-typed block, an unclosed brace), completion by
//! context, hover, go to definition, references, the outline, an evaluation that would run
//! forever, a 1 MB file, 1 000 rapid changes, a client's junk, and shutdown.
//!
//! Timing bounds are generous and stated at each test (the machine is shared); each test
//! prints what it measured.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// How long any answer may take before a test fails (a shared, busy machine).
const ANSWER: Duration = Duration::from_secs(60);

struct Client {
    child: Child,
    /// `None` once closed.
    stdin: Option<ChildStdin>,
    rx: Receiver<Value>,
    next_id: i64,
    /// Messages read while waiting for something else (notifications, mostly).
    stash: Vec<Value>,
}

fn read_message(r: &mut impl BufRead) -> Option<Value> {
    let mut length = None;
    loop {
        let mut line = String::new();
        if r.read_line(&mut line).ok()? == 0 {
            return None;
        }
        let line = line.trim_end();
        if line.is_empty() {
            break;
        }
        if let Some(v) = line.strip_prefix("Content-Length: ") {
            length = v.parse::<usize>().ok();
        }
    }
    let mut body = vec![0; length?];
    r.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

pub fn file_uri(path: &Path) -> String {
    let mut s = String::from("file://");
    for &c in path.to_str().unwrap().as_bytes() {
        if c.is_ascii_alphanumeric() || b"/-._~".contains(&c) {
            s.push(c as char);
        } else {
            s.push_str(&format!("%{c:02X}"));
        }
    }
    s
}

impl Client {
    /// The server started and initialized.
    fn start() -> (Client, Value) {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sppm-lang"))
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("the server starts");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            while let Some(m) = read_message(&mut r) {
                if tx.send(m).is_err() {
                    break;
                }
            }
        });
        let mut c = Client {
            child,
            stdin: Some(stdin),
            rx,
            next_id: 1,
            stash: Vec::new(),
        };
        let init = c.request(
            "initialize",
            json!({ "processId": null, "rootUri": null, "capabilities": {} }),
        );
        c.notify("initialized", json!({}));
        (c, init)
    }

    fn send_raw(&mut self, bytes: &[u8]) {
        let stdin = self.stdin.as_mut().expect("input open");
        stdin.write_all(bytes).unwrap();
        stdin.flush().unwrap();
    }

    fn send(&mut self, v: &Value) {
        let body = serde_json::to_string(v).unwrap();
        self.send_raw(format!("Content-Length: {}\r\n\r\n{body}", body.len()).as_bytes());
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(&json!({ "jsonrpc": "2.0", "method": method, "params": params }));
    }

    /// Sends a request and returns its whole response.
    fn request(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        self.send(&json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params }));
        self.response(id)
    }

    fn response(&mut self, id: i64) -> Value {
        let deadline = Instant::now() + ANSWER;
        loop {
            let m = self
                .next(deadline)
                .unwrap_or_else(|| panic!("no answer to request {id}"));
            if m.get("id") == Some(&json!(id)) && m.get("method").is_none() {
                return m;
            }
            self.stash.push(m);
        }
    }

    fn next(&mut self, deadline: Instant) -> Option<Value> {
        let left = deadline.saturating_duration_since(Instant::now());
        self.rx.recv_timeout(left).ok()
    }

    /// The first published diagnostics for `uri` that `accept` takes, waiting up to `within`.
    fn diagnostics(
        &mut self,
        uri: &str,
        within: Duration,
        accept: impl Fn(&Value) -> bool,
    ) -> Option<Value> {
        let fits = |m: &Value| {
            m["method"] == "textDocument/publishDiagnostics"
                && m["params"]["uri"] == uri
                && accept(&m["params"])
        };
        if let Some(i) = self.stash.iter().position(fits) {
            return Some(self.stash.remove(i)["params"].clone());
        }
        let deadline = Instant::now() + within;
        while let Some(m) = self.next(deadline) {
            if fits(&m) {
                return Some(m["params"].clone());
            }
            self.stash.push(m);
        }
        None
    }

    /// The names of a document's top-level outline entries.
    fn outline(&mut self, uri: &str) -> Vec<String> {
        let symbols = self.request(
            "textDocument/documentSymbol",
            json!({ "textDocument": { "uri": uri } }),
        );
        symbols["result"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["name"].as_str().unwrap().to_string())
            .collect()
    }

    /// Opens every scene of a folder of the repository in turn and hands `check` its path,
    /// text, uri and first diagnostics; returns how many there were.
    fn open_each(
        &mut self,
        dir: &str,
        mut check: impl FnMut(&mut Client, &Path, &str, &str, Value),
    ) -> usize {
        let mut n = 0;
        for e in std::fs::read_dir(repo(dir)).unwrap() {
            let path = e.unwrap().path();
            if path.extension().is_none_or(|x| x != "scn") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let uri = self.open(&path, &text);
            let d = self
                .diagnostics(&uri, ANSWER, |_| true)
                .unwrap_or_else(|| panic!("no diagnostics for {}", path.display()));
            check(self, &path, &text, &uri, d);
            n += 1;
        }
        n
    }

    fn open(&mut self, path: &Path, text: &str) -> String {
        let uri = file_uri(path);
        self.notify(
            "textDocument/didOpen",
            json!({ "textDocument": { "uri": uri, "languageId": "scn", "version": 1, "text": text } }),
        );
        uri
    }

    fn change(&mut self, uri: &str, version: i64, changes: Value) {
        self.notify(
            "textDocument/didChange",
            json!({ "textDocument": { "uri": uri, "version": version }, "contentChanges": changes }),
        );
    }

    fn at(&mut self, method: &str, uri: &str, (line, character): (usize, usize)) -> Value {
        let mut params = json!({
            "textDocument": { "uri": uri },
            "position": { "line": line, "character": character },
        });
        params["context"] = match method {
            "textDocument/references" => json!({ "includeDeclaration": true }),
            "textDocument/completion" => json!({ "triggerKind": 1 }),
            _ => Value::Null,
        };
        let r = self.request(method, params);
        assert!(r.get("error").is_none(), "{method}: {r}");
        r["result"].clone()
    }

    fn labels(&mut self, uri: &str, pos: (usize, usize)) -> Vec<String> {
        let r = self.at("textDocument/completion", uri, pos);
        let items = r
            .as_array()
            .or_else(|| r["items"].as_array())
            .expect("a list");
        let mut items: Vec<&Value> = items.iter().collect();
        items.sort_by_key(|i| i["sortText"].as_str().unwrap_or("").to_string());
        items
            .iter()
            .map(|i| i["label"].as_str().unwrap().to_string())
            .collect()
    }

    /// `shutdown` then `exit`: the server must answer and end with status 0.
    fn finish(mut self) {
        let r = self.request("shutdown", Value::Null);
        assert_eq!(r["result"], Value::Null, "{r}");
        assert!(r.get("error").is_none(), "{r}");
        self.notify("exit", Value::Null);
        let deadline = Instant::now() + ANSWER;
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                assert!(status.success(), "exit status {status}");
                return;
            }
            assert!(Instant::now() < deadline, "the server did not exit");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The server's resident memory in KiB (Linux).
    fn rss_kib(&self) -> Option<u64> {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).ok()?;
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn errors(diags: &Value) -> Vec<String> {
    diags["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["severity"] == 1)
        .map(|d| d["message"].as_str().unwrap().to_string())
        .collect()
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// (line, UTF-16 column) of the first `marker` in `text`, plus `skip` characters.
fn pos(text: &str, marker: &str, skip: usize) -> (usize, usize) {
    let at = text.find(marker).unwrap_or_else(|| panic!("no `{marker}`")) + skip;
    let line = text[..at].matches('\n').count();
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    (line, text[start..at].encode_utf16().count())
}

#[test]
fn initialize_announces_the_features_and_shutdown_exits() {
    let (c, init) = Client::start();
    let caps = &init["result"]["capabilities"];
    for cap in [
        "completionProvider",
        "hoverProvider",
        "definitionProvider",
        "referencesProvider",
        "documentSymbolProvider",
        "textDocumentSync",
    ] {
        assert!(!caps[cap].is_null(), "no {cap}: {init}");
    }
    assert_eq!(init["result"]["serverInfo"]["name"], "sppm-lang");
    c.finish();
}

#[test]
fn every_example_checks_clean_and_has_an_outline() {
    let (mut c, _) = Client::start();
    let n = c.open_each("examples", |c, path, _, uri, d| {
        assert!(errors(&d).is_empty(), "{}: {d}", path.display());
        let names = c.outline(uri);
        assert!(
            names.iter().any(|n| n == "camera"),
            "{}: {names:?}",
            path.display()
        );
    });
    assert!(n >= 10, "only {n} examples");
    c.finish();
}

#[test]
fn hover_definition_references_and_outline_on_an_example() {
    let path = repo("examples/goblet.scn");
    let text = std::fs::read_to_string(&path).unwrap();
    let (mut c, _) = Client::start();
    let uri = c.open(&path, &text);
    assert!(c.diagnostics(&uri, ANSWER, |_| true).is_some());

    // `White` where a quad's material names it: hover shows its declaration.
    let use_at = pos(&text, "material { White }", 11);
    let h = c.at("textDocument/hover", &uri, use_at);
    let shown = h["contents"]["value"].as_str().unwrap();
    assert!(shown.contains("#declare White = material"), "{h}");

    let decl = pos(&text, "#declare White", 9);
    let d = c.at("textDocument/definition", &uri, use_at);
    assert_eq!(d[0]["uri"], uri.as_str());
    assert_eq!(d[0]["range"]["start"]["line"], decl.0);
    assert_eq!(d[0]["range"]["start"]["character"], decl.1);

    // Every line that names `White` as a material, and the declaration.
    let expected: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains("{ White }") || l.starts_with("#declare White"))
        .map(|(i, _)| i)
        .collect();
    let r = c.at("textDocument/references", &uri, use_at);
    let mut lines: Vec<usize> = r
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["range"]["start"]["line"].as_u64().unwrap() as usize)
        .collect();
    lines.dedup();
    assert_eq!(lines, expected);

    // A keyword's line, with the reference's section.
    let h = c.at("textDocument/hover", &uri, pos(&text, "revolve {", 2));
    let shown = h["contents"]["value"].as_str().unwrap();
    assert!(shown.contains("docs/language.md#revolve"), "{h}");

    let names = c.outline(&uri);
    for n in [
        "White",
        "Red",
        "Green",
        "settings",
        "camera",
        "area_light",
        "quad",
        "revolve",
    ] {
        assert!(names.iter().any(|m| m == n), "no `{n}` in {names:?}");
    }
    c.finish();
}

#[test]
fn completion_by_context() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("walls.inc"), "#declare Brick = 1;\n").unwrap();
    let path = dir.path().join("s.scn");
    let text = "#include \"walls.inc\"\n#declare Radius = 1;\n#macro Ball(R) sphere { <0,0,0>, R } #end\ncylinder { <0,0,0>, <0,1,0>, Radius\n  o\n}\n\n#\n#include \"w\n";
    let (mut c, _) = Client::start();
    let uri = c.open(&path, text);

    // In a cylinder: its properties first (the evaluator's table has `open`), then the rest.
    let labels = c.labels(&uri, pos(text, "  o", 3));
    assert_eq!(
        labels[0..4],
        ["translate", "rotate", "scale", "matrix"],
        "{labels:?}"
    );
    assert!(labels[..6].contains(&"open".to_string()), "{labels:?}");
    for l in ["material", "Radius", "Ball", "Brick", "vlength"] {
        assert!(labels.contains(&l.to_string()), "no `{l}` in {labels:?}");
    }
    assert!(
        !labels.contains(&"radiance".to_string()),
        "an area light's property"
    );
    assert!(
        !labels.contains(&"R".to_string()),
        "a parameter outside its macro"
    );

    // At the top level: the kinds of block first.
    let labels = c.labels(&uri, (6, 0));
    assert_eq!(labels[0], "sphere", "{labels:?}");
    assert!(labels.contains(&"camera".to_string()) && labels.contains(&"background".to_string()));
    assert!(!labels.contains(&"open".to_string()));

    // After `#`: the directives.
    let labels = c.labels(&uri, (7, 1));
    for d in ["declare", "include", "macro", "while", "end"] {
        assert!(labels.contains(&d.to_string()), "no `{d}` in {labels:?}");
    }
    // In an include's string: the files beside the document.
    let labels = c.labels(&uri, (8, 11));
    assert_eq!(labels, ["walls.inc"]);
    c.finish();
}

#[test]
fn every_bad_case_gets_its_diagnostics_in_the_document() {
    let (mut c, _) = Client::start();
    let n = c.open_each("tests/bad", |c, path, text, uri, d| {
        let list = d["diagnostics"].as_array().unwrap();
        assert!(!list.is_empty(), "{}: nothing reported", path.display());
        let lines = text.lines().count().max(1) as u64;
        for diag in list {
            let line = diag["range"]["start"]["line"].as_u64().unwrap();
            assert!(line <= lines, "{}: line {line} of {lines}", path.display());
        }
        c.notify(
            "textDocument/didClose",
            json!({ "textDocument": { "uri": uri } }),
        );
    });
    assert!(n > 200, "only {n} cases");
    c.finish();
}

#[test]
fn half_typed_blocks_and_unclosed_braces() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.scn");
    let text = "camera { location <0, 1, -5> look_at <0, 0, 0> }\nsphere { <0, 0, 0>, 1\n  mat";
    let (mut c, _) = Client::start();
    let uri = c.open(&path, text);
    let d = c.diagnostics(&uri, ANSWER, |_| true).unwrap();
    let errs = errors(&d);
    assert!(!errs.is_empty(), "{d}");
    // Completion still knows it is in a sphere.
    let labels = c.labels(&uri, (2, 5));
    assert_eq!(labels[0], "translate", "{labels:?}");
    assert!(labels.contains(&"material".to_string()));
    // Closing the block (a new version) clears the error.
    c.change(&uri, 2, json!([{ "range": { "start": { "line": 2, "character": 2 }, "end": { "line": 2, "character": 5 } }, "text": "material { diffuse rgb <0.8, 0.8, 0.8> } }\nlight { <0, 5, -5> intensity rgb <1, 1, 1> }\n" }]));
    let d = c.diagnostics(&uri, ANSWER, |p| p["version"] == 2).unwrap();
    assert!(errors(&d).is_empty(), "{d}");
    c.finish();
}

#[test]
fn an_endless_evaluation_is_cut_short_and_the_next_change_is_served() {
    // The endless loop ends at the step budget (about 1 s on an idle machine, printed); the
    // bound only tells that from a hang, since the machine's load sets the time. That the fix
    // cancels the check in flight is told by the times' ratio, which the load does not change:
    // uncancelled, the fix would wait for the rest of the endless check (`took` less 0.1 s).
    const BOUND: Duration = Duration::from_secs(30);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.scn");
    let good = "sphere { <0, 0, 0>, 1 }\nlight { <0, 5, -5> intensity rgb <1, 1, 1> }\n";
    let endless = format!("{good}#declare I = 0;\n#while (true)\n  #declare I = I + 1;\n#end\n");
    let (mut c, _) = Client::start();
    let t = Instant::now();
    let uri = c.open(&path, &endless);
    let d = c.diagnostics(&uri, ANSWER, |_| true).unwrap();
    let endless_took = t.elapsed();
    println!("endless loop: diagnostics after {endless_took:?}");
    assert!(!errors(&d).is_empty(), "{d}");
    assert!(endless_took < BOUND, "{endless_took:?}");

    // Mid-edit: another endless version, then at once the fix; only the fix is reported.
    c.change(
        &uri,
        2,
        json!([{ "text": format!("{endless}// still typing\n") }]),
    );
    std::thread::sleep(Duration::from_millis(300));
    let t = Instant::now();
    c.change(&uri, 3, json!([{ "text": good }]));
    let d = c.diagnostics(&uri, ANSWER, |p| p["version"] == 3).unwrap();
    let took = t.elapsed();
    println!("the fixing change: diagnostics after {took:?}");
    assert!(errors(&d).is_empty(), "{d}");
    assert!(
        took < endless_took / 3 + Duration::from_millis(250),
        "the fix took {took:?}, the endless check {endless_took:?}: not cancelled?"
    );
    // Hover answers while that runs and after.
    let h = c.at("textDocument/hover", &uri, (0, 2));
    assert!(h["contents"]["value"].as_str().unwrap().contains("sphere"));
    c.finish();
}

#[test]
fn a_one_megabyte_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.scn");
    let mut text = String::from(
        "#declare Base = 0.1;\ncamera { location <0, 0, -50> look_at <0, 0, 0> }\nlight { <0, 50, -50> intensity rgb <1, 1, 1> }\n",
    );
    let mut i = 0;
    while text.len() < 1 << 20 {
        text.push_str(&format!(
            "sphere {{ <{}, {}, 0>, Base material {{ diffuse rgb <0.5, 0.5, 0.5> }} }}\n",
            i % 100,
            i / 100
        ));
        i += 1;
    }
    let (mut c, _) = Client::start();
    let t = Instant::now();
    let uri = c.open(&path, &text);
    let d = c.diagnostics(&uri, ANSWER, |_| true).unwrap();
    println!("1 MiB, {i} spheres: diagnostics after {:?}", t.elapsed());
    assert!(errors(&d).is_empty(), "{d}");
    let t = Instant::now();
    let last = text.lines().count() - 1;
    let labels = c.labels(&uri, (last, 10));
    assert!(labels.contains(&"Base".to_string()));
    let symbols = c.request(
        "textDocument/documentSymbol",
        json!({ "textDocument": { "uri": uri } }),
    )["result"]
        .clone();
    let n = symbols.as_array().unwrap().len();
    assert!(n > 1000 && n <= 5000, "{n} symbols");
    let last_line = text.lines().last().unwrap();
    let h = c.at(
        "textDocument/hover",
        &uri,
        (last, last_line.find("Base").unwrap() + 1),
    );
    assert!(
        h["contents"]["value"].as_str().unwrap().contains("Base"),
        "{h}"
    );
    println!("completion, outline and hover: {:?}", t.elapsed());
    // An edit at the end of the file (incremental) is checked too.
    c.change(&uri, 2, json!([{ "range": { "start": { "line": last + 1, "character": 0 }, "end": { "line": last + 1, "character": 0 } }, "text": "sphere { <0, 0, 0>, Nope }\n" }]));
    let d = c.diagnostics(&uri, ANSWER, |p| p["version"] == 2).unwrap();
    let errs = errors(&d);
    assert!(errs.iter().any(|e| e.contains("Nope")), "{errs:?}");
    c.finish();
}

#[test]
fn a_thousand_rapid_changes_the_last_state_wins() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.scn");
    let head = "camera { location <0, 0, -5> look_at <0, 0, 0> }\nlight { <0, 5, -5> intensity rgb <1, 1, 1> }\n";
    let (mut c, _) = Client::start();
    let uri = c.open(&path, head);
    c.diagnostics(&uri, ANSWER, |_| true).unwrap();
    let before = c.rss_kib();
    // Each change replaces the third line with a sphere whose radius names an undeclared
    // `LastK` (the first inserts it).
    let line = head.lines().count();
    for k in 0..1000 {
        let end = if k == 0 { line } else { line + 1 };
        c.change(&uri, 2 + k as i64, json!([{ "range": { "start": { "line": line, "character": 0 }, "end": { "line": end, "character": 0 } }, "text": format!("sphere {{ <0, 0, 0>, Last{k} }}\n") }]));
    }
    let last = 2 + 999;
    let d = c
        .diagnostics(&uri, ANSWER, |p| p["version"] == last)
        .unwrap();
    let errs = errors(&d);
    // The final text was checked, and only it.
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert!(errs[0].contains("Last999"), "{errs:?}");
    // Nothing older arrives afterwards.
    let later = c.diagnostics(&uri, Duration::from_secs(1), |p| p["version"] != last);
    assert!(later.is_none(), "{later:?}");
    // The final text is what hover reads.
    let h = c.at("textDocument/hover", &uri, (line, 2));
    assert!(h["contents"]["value"].as_str().unwrap().contains("sphere"));
    if let (Some(a), Some(b)) = (before, c.rss_kib()) {
        println!("resident memory: {a} KiB before, {b} KiB after 1 000 changes");
        assert!(b < a + 200 * 1024, "{a} KiB -> {b} KiB");
    }
    c.finish();
}

#[test]
fn unsaved_included_files_are_read_from_the_editor() {
    let dir = tempfile::tempdir().unwrap();
    let (main, lib) = (dir.path().join("s.scn"), dir.path().join("lib.inc"));
    std::fs::write(&lib, "// saved: declares nothing\n").unwrap();
    let text = "#include \"lib.inc\"\ncamera { location <0, 0, -5> look_at <0, 0, 0> }\nlight { <0, 5, -5> intensity rgb <1, 1, 1> }\nsphere { <0, 0, 0>, Size }\n";
    let (mut c, _) = Client::start();
    let lib_uri = c.open(&lib, "#declare Size = 2;\n");
    let uri = c.open(&main, text);
    let d = c.diagnostics(&uri, ANSWER, |_| true).unwrap();
    assert!(
        errors(&d).is_empty(),
        "the unsaved buffer declares Size: {d}"
    );
    let def = c.at("textDocument/definition", &uri, (3, 21));
    assert_eq!(def[0]["uri"], lib_uri.as_str(), "{def}");
    // Editing the include checks the scene again.
    c.change(&lib_uri, 2, json!([{ "text": "#declare Other = 2;\n" }]));
    let d = c
        .diagnostics(&uri, ANSWER, |p| !errors(p).is_empty())
        .unwrap();
    assert!(errors(&d)[0].contains("Size"), "{d}");
    c.finish();
}

#[test]
fn junk_from_the_client_is_survived() {
    let (mut c, _) = Client::start();
    c.send_raw(b"Content-Length: 9\r\n\r\n{not json");
    c.send_raw(b"this is not a header\r\n\r\n");
    let r = c.request("textDocument/unknownThing", json!({}));
    assert_eq!(r["error"]["code"], -32601, "{r}");
    let r = c.request("textDocument/hover", json!({ "bogus": 1 }));
    assert_eq!(r["error"]["code"], -32602, "{r}");
    c.notify("$/somethingNew", json!({ "x": 1 }));
    c.notify("textDocument/didChange", json!({ "textDocument": { "uri": "file:///never/opened.scn", "version": 3 }, "contentChanges": [{ "text": "x" }] }));
    // A position far outside the document and a document never opened.
    let dir = tempfile::tempdir().unwrap();
    let uri = c.open(&dir.path().join("s.scn"), "sphere { <0,0,0>, 1 }\n");
    let r = c.request(
        "textDocument/hover",
        json!({ "textDocument": { "uri": uri }, "position": { "line": 999, "character": 999 } }),
    );
    assert!(r.get("error").is_none(), "{r}");
    let r = c.request("textDocument/completion", json!({ "textDocument": { "uri": "file:///never/opened.scn" }, "position": { "line": 0, "character": 0 } }));
    assert_eq!(r["result"], Value::Null, "{r}");
    // Still serving.
    let h = c.at("textDocument/hover", &uri, (0, 2));
    assert!(
        h["contents"]["value"].as_str().unwrap().contains("sphere"),
        "{h}"
    );
    c.finish();
}

#[test]
fn an_oversized_message_is_read_past_and_the_end_of_input_ends_the_server() {
    // A header that announces 100 GB: the server must not try to hold it. The input then
    // ends (the editor quit without `shutdown`): exit status 1, within the bound.
    let (mut c, _) = Client::start();
    c.send_raw(b"Content-Length: 100000000000\r\n\r\n{\"jsonrpc\":\"2.0\"");
    drop(c.stdin.take());
    let deadline = Instant::now() + ANSWER;
    loop {
        if let Some(status) = c.child.try_wait().unwrap() {
            assert_eq!(status.code(), Some(1), "{status}");
            break;
        }
        assert!(Instant::now() < deadline, "the server did not end");
        std::thread::sleep(Duration::from_millis(20));
    }
}
