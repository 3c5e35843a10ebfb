//! `watch --serve` under attack: each test starts the real `sppm-lang watch --serve` on a free
//! loopback port and sends it what a hostile page, a local user or a broken client would
//! (loopback only; every loop bounded in count and time).
//!
//! The scene prints a secret with `#warning`, which the page's status carries: a refused
//! request must never see it, an admitted one does (so the checks are not vacuous).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::running;
use running::Running;

const SECRET: &str = "secret-7f3a";

/// A small scene that renders for a long time and says the secret.
fn scene(resolution: u32) -> String {
    format!(
        "#warning \"{SECRET}\"\n\
         settings {{ resolution <{resolution}, {resolution}>  iterations 100000  photons 2000  seed 1 }}\n\
         camera {{ location <0, 1, 3.9>  look_at <0, 1, 0>  fov 40 }}\n\
         area_light {{ quad {{ <-0.25, 1.98, -0.25>, <0.5, 0, 0>, <0, 0, 0.5> }}  radiance rgb <17, 12, 4> }}\n\
         quad {{ <-1, 0, -1>, <2, 0, 0>, <0, 0, 2>  material {{ diffuse rgb <0.7, 0.7, 0.7> }} }}\n"
    )
}

/// A running `watch --serve` and what its URL says.
struct Live {
    watch: Running,
    _dir: tempfile::TempDir,
    /// `127.0.0.1:PORT`.
    addr: String,
    port: u16,
    token: Option<String>,
}

impl Live {
    fn start(resolution: u32, extra: &[&str]) -> Live {
        Self::start_wrapped(resolution, extra, &[])
    }

    /// Started through `wrapper` (e.g. `prlimit ... --`) when it is not empty.
    fn start_wrapped(resolution: u32, extra: &[&str], wrapper: &[&str]) -> Live {
        let dir = tempfile::tempdir().unwrap();
        let scene_path = dir.path().join("s.scn");
        std::fs::write(&scene_path, scene(resolution)).unwrap();
        let exe = env!("CARGO_BIN_EXE_sppm-lang");
        let mut command = match wrapper.split_first() {
            Some((first, rest)) => {
                let mut c = Command::new(first);
                c.args(rest).arg(exe);
                c
            }
            None => Command::new(exe),
        };
        command
            .args([
                "watch",
                scene_path.to_str().unwrap(),
                "--serve",
                "--port",
                "0",
            ])
            .args(["--no-clear", "--threads", "1"])
            .args(extra)
            .current_dir(dir.path());
        let mut watch = Running::spawn(command);
        let line = watch.expect("serving the live view on ", Duration::from_secs(60));
        let url = line
            .split("serving the live view on ")
            .nth(1)
            .unwrap()
            .trim();
        let rest = url.strip_prefix("http://").expect(url);
        let (addr, path) = rest.split_once('/').unwrap();
        let port = addr.rsplit_once(':').unwrap().1.parse().unwrap();
        let token = path.strip_prefix("?token=").map(str::to_string);
        Live {
            watch,
            _dir: dir,
            addr: addr.to_string(),
            port,
            token,
        }
    }

    fn pid(&self) -> u32 {
        self.watch.child.id()
    }

    /// `?token=...` for a path.
    fn with_token(&self, path: &str) -> String {
        match &self.token {
            Some(t) => format!("{path}?token={t}"),
            None => path.to_string(),
        }
    }

    /// A GET of `path` as a browser on this page sends it (right Host, the token).
    fn get(&self, path: &str) -> Answer {
        let head = format!(
            "GET {} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
            self.with_token(path),
            self.addr
        );
        self.send(head.as_bytes())
    }

    /// Sends `raw` on a new connection and reads the answer (to its end, or 5 s).
    fn send(&self, raw: &[u8]) -> Answer {
        let mut s = TcpStream::connect(&self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        s.write_all(raw).unwrap();
        Answer::read(&mut s)
    }

    /// Waits until the page has an image.
    fn wait_for_image(&self) {
        let deadline = Instant::now() + Duration::from_secs(60);
        while self.get("/image").status != 200 {
            assert!(Instant::now() < deadline, "no image within 60 s");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn assert_alive(&mut self) {
        assert!(
            self.watch.child.try_wait().unwrap().is_none(),
            "watch exited:\n{}",
            self.watch.log.join("\n")
        );
        let lines = self.watch.drain(Duration::from_millis(50));
        assert!(
            !lines.iter().any(|l| l.contains("panicked")),
            "{}",
            lines.join("\n")
        );
    }
}

/// An HTTP answer as read from the socket.
struct Answer {
    status: u16,
    head: String,
    body: Vec<u8>,
}

impl Answer {
    fn read(s: &mut TcpStream) -> Answer {
        let mut raw = Vec::new();
        let mut buf = [0u8; 65536];
        loop {
            match s.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => raw.extend_from_slice(&buf[..n]),
            }
        }
        Self::parse(&raw)
    }

    fn parse(raw: &[u8]) -> Answer {
        let end = raw
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .map_or(raw.len(), |i| i + 4);
        let head = String::from_utf8_lossy(&raw[..end]).into_owned();
        let status = head
            .split(' ')
            .nth(1)
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        Answer {
            status,
            head,
            body: raw[end..].to_vec(),
        }
    }

    fn header(&self, name: &str) -> Option<String> {
        self.head.lines().find_map(|l| {
            let (n, v) = l.split_once(':')?;
            n.eq_ignore_ascii_case(name).then(|| v.trim().to_string())
        })
    }

    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

/// The first `data:` event of `/events` sent with `head`, read within `within`.
fn first_event(addr: &str, head: &str, within: Duration) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(within)).unwrap();
    s.write_all(head.as_bytes()).unwrap();
    let started = Instant::now();
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    while started.elapsed() < within {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => raw.extend_from_slice(&buf[..n]),
        }
        // The stream is chunked: the first event is whole once its JSON's end has come.
        let text = String::from_utf8_lossy(&raw);
        if text
            .split_once("\ndata: {")
            .is_some_and(|(_, event)| event.contains("}\n\n"))
        {
            break;
        }
    }
    let answer = Answer::parse(&raw);
    (answer.status, answer.text())
}

/// Resident memory of a process, in bytes.
fn rss(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kb: u64 = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap();
    kb * 1024
}

/// The process's resident memory now is at most `margin` above `before` (printed with `what`).
fn assert_memory_held(pid: u32, what: &str, before: u64, margin: u64) {
    let after = rss(pid);
    println!(
        "{what}resident memory {} MiB before, {} MiB after",
        before >> 20,
        after >> 20
    );
    assert!(
        after <= before + margin,
        "grew by {} MiB",
        (after - before) >> 20
    );
}

#[test]
fn only_the_user_gets_in() {
    let mut live = Live::start(32, &[]);
    let token = live.token.clone().expect("the printed URL carries a token");
    assert_eq!(token.len(), 32);
    let addr = live.addr.clone();
    let port = live.port;
    live.wait_for_image();

    // A page whose name was re-pointed at 127.0.0.1 sends its own Host, token or not.
    for host in [
        "rebound.example".to_string(),
        format!("rebound.example:{port}"),
        format!("127.0.0.1:{}", port.wrapping_add(1)),
        String::new(),
    ] {
        for path in ["/", "/events", "/image"] {
            let a = live.send(
                format!(
                    "GET {path}?token={token} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
                )
                .as_bytes(),
            );
            assert_eq!(a.status, 403, "Host `{host}` {path}: {}", a.head);
            assert!(!a.text().contains(SECRET));
        }
    }
    // No Host at all (HTTP/1.0).
    let a = live.send(format!("GET /events?token={token} HTTP/1.0\r\n\r\n").as_bytes());
    assert_eq!(a.status, 403, "{}", a.head);

    // Another site's page opening the event stream or fetching the image.
    for origin in [
        "http://evil.example",
        "null",
        "https://127.0.0.1",
        "http://127.0.0.1",
    ] {
        for path in ["/events", "/image", "/"] {
            let a = live.send(
                format!(
                    "GET {path}?token={token} HTTP/1.1\r\nHost: {addr}\r\nOrigin: {origin}\r\n\
                     Connection: close\r\n\r\n"
                )
                .as_bytes(),
            );
            assert_eq!(a.status, 403, "Origin `{origin}` {path}: {}", a.head);
            assert!(!a.text().contains(SECRET));
        }
    }

    // Another local user: the right Host, no token or a wrong one, or another port's cookie.
    // The token with its last character changed (a fixed `0` would be the token itself one
    // time in sixteen).
    let last = if token.ends_with('0') { '1' } else { '0' };
    let wrong = format!("{}{last}", &token[..31]);
    assert_ne!(wrong, token);
    for (query, cookie) in [
        (String::new(), String::new()),
        (format!("?token={wrong}"), String::new()),
        (format!("?token={token}x"), String::new()),
        (
            String::new(),
            format!("Cookie: sppm_lang_{}={token}\r\n", port.wrapping_add(1)),
        ),
        (
            String::new(),
            format!("Cookie: sppm_lang_{port}={wrong}\r\n"),
        ),
    ] {
        for path in ["/", "/events", "/image"] {
            let a = live.send(
                format!(
                    "GET {path}{query} HTTP/1.1\r\nHost: {addr}\r\n{cookie}Connection: close\r\n\r\n"
                )
                .as_bytes(),
            );
            assert_eq!(a.status, 403, "`{query}` `{cookie}` {path}: {}", a.head);
            assert!(!a.text().contains(SECRET));
        }
    }

    // The user: the printed URL sets the cookie and sends the page on without the token.
    let a = live.get("/");
    assert_eq!(a.status, 303, "{}", a.head);
    assert_eq!(a.header("location").as_deref(), Some("/"));
    let cookie = a.header("set-cookie").expect("a cookie");
    assert!(
        cookie.contains("HttpOnly") && cookie.contains("SameSite=Lax"),
        "{cookie}"
    );
    let pair = cookie.split(';').next().unwrap().to_string();
    assert_eq!(pair, format!("sppm_lang_{port}={token}"));
    let with_cookie = |path: &str| {
        format!(
            "GET {path} HTTP/1.1\r\nHost: {addr}\r\nCookie: {pair}\r\nConnection: close\r\n\r\n"
        )
    };
    let page = live.send(with_cookie("/").as_bytes());
    assert_eq!(page.status, 200, "{}", page.head);
    assert!(page.text().contains("<html"));
    // A same-origin request from the page itself is admitted (the browser's Origin).
    let a = live.send(
        format!(
            "GET /image HTTP/1.1\r\nHost: localhost:{port}\r\nOrigin: http://localhost:{port}\r\n\
             Cookie: {pair}\r\nConnection: close\r\n\r\n"
        )
        .as_bytes(),
    );
    assert_eq!(a.status, 200, "{}", a.head);

    // A new tab gets the status (with the image's number) at once.
    let started = Instant::now();
    let (status, text) = first_event(&addr, &with_cookie("/events"), Duration::from_secs(5));
    let took = started.elapsed();
    assert_eq!(status, 200);
    assert!(
        text.contains(SECRET),
        "the admitted stream carries the status: {text:.300}"
    );
    assert!(!text.contains("\"image\":0"), "{text:.300}");
    assert!(took < Duration::from_secs(1), "first event after {took:?}");
    println!("a new tab's first event came after {took:?}");
    live.assert_alive();
}

#[test]
fn no_token_admits_local_pages_but_still_checks_host_and_origin() {
    let live = Live::start(16, &["--no-token"]);
    assert!(live.token.is_none());
    assert_eq!(live.get("/").status, 200);
    let a = live.send(
        format!(
            "GET /events HTTP/1.1\r\nHost: {}\r\nOrigin: http://evil.example\r\nConnection: close\r\n\r\n",
            live.addr
        )
        .as_bytes(),
    );
    assert_eq!(a.status, 403);
    let a = live.send(b"GET / HTTP/1.1\r\nHost: evil.example\r\nConnection: close\r\n\r\n");
    assert_eq!(a.status, 403);
}

#[test]
fn bodies_and_other_methods_are_refused_and_the_server_keeps_serving() {
    let mut live = Live::start(16, &[]);
    let addr = live.addr.clone();
    let token = live.token.clone().unwrap();
    // A cross-origin form can send these; 200 of them, each on its own connection.
    for i in 0..200 {
        let a = live.send(
            format!(
                "POST /?token={token} HTTP/1.1\r\nHost: {addr}\r\nContent-Type: text/plain\r\n\
                 Content-Length: 11\r\n\r\nhello=world"
            )
            .as_bytes(),
        );
        assert_eq!(a.status, 405, "POST #{i}: {}", a.head);
        assert_eq!(a.header("allow").as_deref(), Some("GET, HEAD"));
    }
    for method in ["PUT", "DELETE", "OPTIONS", "PATCH", "BREW", "CONNECT"] {
        let a = live.send(
            format!("{method} / HTTP/1.1\r\nHost: {addr}\r\nContent-Length: 0\r\n\r\n").as_bytes(),
        );
        assert!(a.status == 405 || a.status == 400, "{method}: {}", a.head);
    }
    // A chunked body and a huge declared one.
    let a = live.send(
        format!(
            "POST / HTTP/1.1\r\nHost: {addr}\r\nTransfer-Encoding: chunked\r\n\r\n5\r\nhello\r\n0\r\n\r\n"
        )
        .as_bytes(),
    );
    assert_eq!(a.status, 405, "{}", a.head);
    let a = live.send(
        format!("GET /image?token={token} HTTP/1.1\r\nHost: {addr}\r\nContent-Length: 99999999999\r\n\r\n")
            .as_bytes(),
    );
    assert_eq!(a.status, 400, "{}", a.head);
    // HEAD is answered without a body.
    let a = live.send(
        format!("HEAD /events?token={token} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n")
            .as_bytes(),
    );
    assert_eq!(a.status, 200, "{}", a.head);
    assert!(a.body.is_empty());
    // Still serving.
    assert_eq!(live.get("/").status, 303);
    live.assert_alive();
}

#[test]
fn a_huge_request_line_is_cut_off_with_bounded_memory() {
    /// What the server may grow by while it cuts off the attack (its buffers are 16 KiB a
    /// connection; the rest is allocator slack).
    const MARGIN: u64 = 16 << 20;
    let mut live = Live::start(16, &[]);
    live.wait_for_image();
    let before = rss(live.pid());
    // 100 MB of request line (and, on a second connection, of one header), sent until the
    // server closes the connection.
    for prefix in ["GET /", "GET / HTTP/1.1\r\nHost: x\r\nX-Long: "] {
        let mut s = TcpStream::connect(&live.addr).unwrap();
        s.set_write_timeout(Some(Duration::from_secs(5))).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        s.write_all(prefix.as_bytes()).unwrap();
        let chunk = vec![b'a'; 1 << 20];
        let mut sent = 0usize;
        let started = Instant::now();
        while sent < 100 << 20 {
            match s.write(&chunk) {
                Ok(n) => sent += n,
                Err(_) => break,
            }
            assert!(started.elapsed() < Duration::from_secs(30), "not cut off");
        }
        let answer = Answer::read(&mut s);
        println!(
            "`{}…`: cut off after {} KiB sent, answer {}",
            prefix.escape_debug(),
            sent >> 10,
            answer.status
        );
        assert!(sent < 100 << 20, "the server read 100 MB of head");
        assert!(
            [0, 414, 431, 400].contains(&answer.status),
            "{}",
            answer.head
        );
    }
    assert_memory_held(live.pid(), "", before, MARGIN);
    assert_eq!(live.get("/").status, 303);
    live.assert_alive();
}

#[test]
fn a_client_that_stops_reading_delays_nobody() {
    // A 1024x1024 image is 12.6 MB: more than the socket buffers hold.
    let mut live = Live::start(1024, &["--no-preview"]);
    live.wait_for_image();
    let image = live.get("/image");
    assert_eq!(image.status, 200);
    let len = image.body.len();
    assert!(len > 12 << 20, "{len}");
    // Clients that ask for the image and never read it, in every image slot.
    let token = live.token.clone().unwrap();
    let mut stalled = Vec::new();
    for _ in 0..4 {
        let mut s = TcpStream::connect(&live.addr).unwrap();
        s.write_all(
            format!(
                "GET /image?token={token} HTTP/1.1\r\nHost: {}\r\n\r\n",
                live.addr
            )
            .as_bytes(),
        )
        .unwrap();
        stalled.push(s);
    }
    std::thread::sleep(Duration::from_millis(300));
    // Everyone else is served at once: the page, the events, and a polite refusal of a fifth
    // image while the slots are held.
    let started = Instant::now();
    assert_eq!(live.get("/").status, 303);
    let page_took = started.elapsed();
    let started = Instant::now();
    let head = format!(
        "GET /events?token={token} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
        live.addr
    );
    let (status, _) = first_event(&live.addr, &head, Duration::from_secs(5));
    let events_took = started.elapsed();
    assert_eq!(status, 200);
    let fifth = live.get("/image");
    println!(
        "with 4 stalled image readers: page in {page_took:?}, first event in {events_took:?}, \
         a fifth image got {}",
        fifth.status
    );
    assert!(page_took < Duration::from_secs(1), "{page_took:?}");
    assert!(events_took < Duration::from_secs(1), "{events_took:?}");
    assert_eq!(fifth.status, 503, "{}", fifth.head);
    // The stalled clients are dropped once their writes make no progress for the stall limit
    // (10 s); the image is served again.
    let deadline = Instant::now() + Duration::from_secs(25);
    loop {
        let a = live.get("/image");
        if a.status == 200 && a.body.len() == len {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "image slots never freed: {}",
            a.head
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    drop(stalled);
    live.assert_alive();
}

#[test]
fn the_open_file_limit_is_survived() {
    let Ok(status) = Command::new("prlimit").arg("--version").output() else {
        panic!("prlimit (util-linux) is needed for this test");
    };
    assert!(status.status.success());
    let mut live = Live::start_wrapped(16, &[], &["prlimit", "--nofile=48:48", "--"]);
    live.wait_for_image();
    // Far more connections than descriptors; the kernel queues the ones not accepted.
    let mut held = Vec::new();
    for _ in 0..120 {
        match TcpStream::connect(&live.addr) {
            Ok(s) => held.push(s),
            Err(_) => break,
        }
    }
    std::thread::sleep(Duration::from_millis(500));
    live.assert_alive();
    println!("held {} connections", held.len());
    drop(held);
    // Once they close, the server serves again.
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let mut s = TcpStream::connect(&live.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
        let head = format!(
            "GET / HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
            live.addr
        );
        if s.write_all(head.as_bytes()).is_ok() && Answer::read(&mut s).status == 403 {
            break;
        }
        assert!(Instant::now() < deadline, "the server did not recover");
        std::thread::sleep(Duration::from_millis(200));
    }
    live.assert_alive();
    let log = live.watch.log.join("\n");
    assert!(
        log.contains("cannot accept a connection"),
        "the limit was not reached (raise the connection count):\n{log}"
    );
}

#[test]
fn connections_past_the_cap_are_refused_and_idle_ones_are_closed() {
    let mut live = Live::start(16, &[]);
    live.wait_for_image();
    // Idle connections (no request) in every slot, then more.
    let mut idle = Vec::new();
    for _ in 0..128 {
        idle.push(TcpStream::connect(&live.addr).unwrap());
    }
    std::thread::sleep(Duration::from_millis(300));
    let mut over = TcpStream::connect(&live.addr).unwrap();
    over.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let refused = Answer::read(&mut over);
    assert_eq!(refused.status, 503, "{}", refused.head);
    // The idle ones are closed by the server once the head timeout (10 s) passes.
    let started = Instant::now();
    for s in &mut idle {
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        let mut byte = [0u8; 1];
        let n = s.read(&mut byte).unwrap_or(0);
        assert_eq!(n, 0, "an idle connection got data");
    }
    let took = started.elapsed();
    println!("128 idle connections closed by the server within {took:?}");
    assert!(took < Duration::from_secs(15), "{took:?}");
    assert_eq!(live.get("/").status, 303);
    live.assert_alive();
    assert!(
        live.watch
            .log
            .iter()
            .any(|l| l.contains("connections are open; further ones are refused")),
        "{}",
        live.watch.log.join("\n")
    );
}

/// Tabs that never read while the scene prints a thousand long messages: each tab holds at
/// most one status message (bounded in size and shared), so memory stays flat.
#[test]
fn event_streams_that_do_not_read_hold_little() {
    /// Each stalled stream may hold one status message (at most 256 KiB) and its buffers.
    const MARGIN: u64 = 32 << 20;
    let dir = tempfile::tempdir().unwrap();
    let mut live = Live::start(16, &[]);
    live.wait_for_image();
    let before = rss(live.pid());
    let token = live.token.clone().unwrap();
    // Every stream slot but one (the reading tab below takes it).
    let mut stalled = Vec::new();
    for _ in 0..31 {
        let mut s = TcpStream::connect(&live.addr).unwrap();
        s.write_all(
            format!(
                "GET /events?token={token} HTTP/1.1\r\nHost: {}\r\n\r\n",
                live.addr
            )
            .as_bytes(),
        )
        .unwrap();
        stalled.push(s);
    }
    // A save that prints 1 000 messages of 8 000 characters, then a few more status changes.
    let loud = format!(
        "#declare Long = \"{}\";\n#for (I, 1, 1000) #debug Long + str(I) #end\n{}",
        "x".repeat(8000),
        // Another seed: a scene that differs, so that it is rendered (an unchanged one is not).
        scene(16).replace("seed 1", "seed 2")
    );
    let scene_path = live._dir.path().join("s.scn");
    std::fs::write(&scene_path, &loud).unwrap();
    live.watch
        .expect("render #2 started", Duration::from_secs(60));
    std::thread::sleep(Duration::from_secs(3));
    let what = "31 stalled event streams, 1000 messages of 8 KB: ";
    assert_memory_held(live.pid(), what, before, MARGIN);
    // A reading tab still gets the status, with the messages that fit and the count of the
    // rest.
    let head = format!(
        "GET /events?token={token} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
        live.addr
    );
    let (status, text) = first_event(&live.addr, &head, Duration::from_secs(5));
    assert_eq!(status, 200);
    assert!(text.contains("\"more\":"), "{:.200}", text);
    drop(stalled);
    drop(dir);
    live.assert_alive();
}
