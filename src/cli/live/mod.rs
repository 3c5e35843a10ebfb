//! `watch --serve`: a local web page that shows the render as it progresses.
//!
//! The watch loop and its render thread publish into a [`Hub`]: the latest status (what runs,
//! iteration, photons/s, diagnostics) and the latest image, linear RGB. Nothing is queued: a
//! newer status or image replaces the older one, so a slow or closed browser tab never makes
//! anything grow. The HTTP side ([`Server`], on `tiny_http`) serves
//!
//! - `/`: the page (static HTML and JavaScript built into the binary);
//! - `/events`: server-sent events, one `data:` line of JSON per status change (a tab that
//!   misses some sees the latest), and a comment every few seconds so that a closed tab is
//!   noticed and its thread ends;
//! - `/image`: the latest image as 16 bytes of header (width, height, full width, full height,
//!   u32 little-endian) and then `width * height * 3` linear f32 values, row 0 at the top. A
//!   preview is smaller than the full size; the page draws it scaled up to the full size.
//!
//! The page tone-maps the linear image itself (exposure slider, sRGB curve) and reads out the
//! linear value under the cursor.

mod view;

use std::io::Write;
use std::net::{Ipv4Addr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use sppm_lang::film::Image;

pub use view::{DiagnosticView, diagnostics_view};

/// The page, built into the binary.
const PAGE: &str = include_str!("page.html");
/// Most event streams (browser tabs) served at once; more get "503 busy".
const MAX_STREAMS: usize = 64;

/// Largest request body `tiny_http` reads into memory itself (a larger one it skips when the
/// request is dropped by allocating the declared length at once, which a hostile length turns
/// into an abort).
const BUFFERED_BODY: usize = 1024;

/// Requests with a larger declared body (the page sends none) are left unanswered; after this
/// many the server stops (each keeps its connection), and `watch` goes on without the page.
const MAX_BODY_REQUESTS: usize = 64;
/// How often an idle event stream sends a comment (finds closed tabs, keeps proxies open).
const KEEP_ALIVE: Duration = Duration::from_secs(5);

/// What the page shows besides the image.
#[derive(Debug, Clone, Default)]
pub struct Status {
    /// The scene's file name.
    pub scene: String,
    /// `rendering`, `finished`, `errors`, `failed`, `empty`, `cancelled` or `starting`.
    pub state: &'static str,
    /// A one-line human summary of `state`.
    pub message: String,
    pub round: u32,
    /// `preview` or `full` while rendering.
    pub stage: &'static str,
    pub iteration: u32,
    pub iterations: u32,
    /// Seconds of rendering of the current stage.
    pub elapsed: f64,
    pub photons_per_second: f64,
    /// When the save that started this round happened.
    pub saved_at: Option<Instant>,
    /// The scene's exposure (the page's slider multiplies it).
    pub exposure: f64,
    /// Errors and warnings of the last load (errors mean the image shown is the last good one).
    pub diagnostics: Vec<DiagnosticView>,
}

/// The image as sent to the page.
struct Frame {
    seq: u64,
    bytes: Arc<Vec<u8>>,
}

struct State {
    seq: u64,
    status: Status,
    frame: Option<Frame>,
}

/// The latest status and image, shared by the watch loop and the page's connections.
pub struct Hub {
    state: Mutex<State>,
    changed: Condvar,
}

impl Hub {
    pub fn new(scene: String) -> Arc<Self> {
        Arc::new(Self {
            state: Mutex::new(State {
                seq: 1,
                status: Status {
                    scene,
                    state: "starting",
                    exposure: 1.0,
                    ..Status::default()
                },
                frame: None,
            }),
            changed: Condvar::new(),
        })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere while holding the lock leaves plain data: keep serving it.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Changes the status and wakes every event stream.
    pub fn update(&self, change: impl FnOnce(&mut Status)) {
        let mut s = self.lock();
        change(&mut s.status);
        s.seq += 1;
        self.changed.notify_all();
    }

    /// Replaces the image (shown at `full` size) and changes the status in one step.
    pub fn publish(&self, image: &Image, full: (u32, u32), change: impl FnOnce(&mut Status)) {
        let bytes = Arc::new(encode(image, full));
        let mut s = self.lock();
        let seq = s.seq + 1;
        s.frame = Some(Frame { seq, bytes });
        change(&mut s.status);
        s.seq = seq;
        self.changed.notify_all();
    }

    /// The status JSON once it is newer than `seen` (or `None` after `timeout`).
    fn wait_newer(&self, seen: u64, timeout: Duration) -> Option<(u64, String)> {
        let guard = self.lock();
        let (s, _) = self
            .changed
            .wait_timeout_while(guard, timeout, |s| s.seq <= seen)
            .unwrap_or_else(|e| e.into_inner());
        (s.seq > seen).then(|| {
            let image = s.frame.as_ref().map_or(0, |f| f.seq);
            (s.seq, view::status_json(&s.status, image))
        })
    }

    fn frame(&self) -> Option<(u64, Arc<Vec<u8>>)> {
        self.lock().frame.as_ref().map(|f| (f.seq, f.bytes.clone()))
    }
}

/// The `/image` body: the header, then linear RGB as f32 little-endian.
fn encode(image: &Image, full: (u32, u32)) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + image.pixels.len() * 12);
    for v in [image.width, image.height, full.0, full.1] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for p in &image.pixels {
        for c in p {
            out.extend_from_slice(&(*c as f32).to_le_bytes());
        }
    }
    out
}

/// The HTTP server, answering on its own thread until the process ends.
pub struct Server {
    pub url: String,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0: any free port) and serves `hub`.
    pub fn start(port: u16, hub: Arc<Hub>) -> Result<Server, String> {
        let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
        let server = tiny_http::Server::http(addr).map_err(|e| {
            let taken = e
                .downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::AddrInUse);
            if taken {
                format!(
                    "cannot serve the page on {addr}: the port is in use (another program, or \
                     another `watch --serve`); choose another with --port, or --port 0 for any \
                     free port"
                )
            } else {
                format!("cannot serve the page on {addr}: {e}")
            }
        })?;
        let bound = server.server_addr().to_ip().map_or(port, |a| a.port());
        let url = format!("http://127.0.0.1:{bound}/");
        std::thread::Builder::new()
            .name("live-server".into())
            .spawn(move || serve(server, hub))
            .map_err(|e| format!("cannot start the page's server thread: {e}"))?;
        Ok(Server { url })
    }
}

fn serve(server: tiny_http::Server, hub: Arc<Hub>) {
    let streams = Arc::new(AtomicUsize::new(0));
    let mut with_body = 0;
    for request in server.incoming_requests() {
        if request.body_length().is_some_and(|n| n > BUFFERED_BODY) {
            // Neither answered nor dropped: dropping it would make `tiny_http` allocate the
            // declared length to skip the body.
            std::mem::forget(request);
            with_body += 1;
            if with_body >= MAX_BODY_REQUESTS {
                return;
            }
            continue;
        }
        let path = request.url().split('?').next().unwrap_or("").to_string();
        let result = match path.as_str() {
            "/" | "/index.html" => request.respond(with_headers(
                tiny_http::Response::from_string(PAGE),
                &[("Content-Type", "text/html; charset=utf-8")],
            )),
            "/image" => match hub.frame() {
                Some((seq, bytes)) => request.respond(with_headers(
                    tiny_http::Response::from_data(bytes.as_slice()),
                    &[
                        ("Content-Type", "application/octet-stream"),
                        ("Cache-Control", "no-store"),
                        ("X-Image-Seq", &seq.to_string()),
                    ],
                )),
                None => request.respond(tiny_http::Response::empty(204)),
            },
            "/events" => {
                if streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
                    streams.fetch_sub(1, Ordering::SeqCst);
                    request.respond(tiny_http::Response::from_string("busy").with_status_code(503))
                } else {
                    let (hub, count) = (hub.clone(), streams.clone());
                    let spawned = std::thread::Builder::new()
                        .name("live-events".into())
                        .spawn(move || {
                            stream_events(request.into_writer(), &hub);
                            count.fetch_sub(1, Ordering::SeqCst);
                        });
                    if spawned.is_err() {
                        // The request went with the closure; its connection is closed.
                        streams.fetch_sub(1, Ordering::SeqCst);
                    }
                    Ok(())
                }
            }
            _ => {
                request.respond(tiny_http::Response::from_string("not found").with_status_code(404))
            }
        };
        // A browser that went away mid-answer is not an error of the server.
        let _ = result;
    }
}

/// `response` with the headers that are valid (all of them here: ASCII constants and numbers).
fn with_headers<R: std::io::Read>(
    mut response: tiny_http::Response<R>,
    headers: &[(&str, &str)],
) -> tiny_http::Response<R> {
    for (name, value) in headers {
        if let Ok(h) = tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()) {
            response.add_header(h);
        }
    }
    response
}

/// One tab's event stream: the latest status whenever it changes; returns when the tab is gone.
fn stream_events(mut out: Box<dyn Write + Send>, hub: &Hub) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                Connection: close\r\n\r\nretry: 1000\n\n";
    if out
        .write_all(head.as_bytes())
        .and_then(|_| out.flush())
        .is_err()
    {
        return;
    }
    let mut seen = 0;
    loop {
        let message = match hub.wait_newer(seen, KEEP_ALIVE) {
            Some((seq, json)) => {
                seen = seq;
                format!("data: {json}\n\n")
            }
            None => ": alive\n\n".to_string(),
        };
        if out
            .write_all(message.as_bytes())
            .and_then(|_| out.flush())
            .is_err()
        {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Latest wins: a reader that missed several updates gets the newest status and image
    /// once, and nothing is kept of the older ones.
    #[test]
    fn a_late_reader_sees_only_the_latest() {
        let hub = Hub::new("s.scn".into());
        for i in 1..=3u32 {
            let mut img = Image::new(2, 1);
            img.pixels[0] = [f64::from(i), 0.0, 0.0];
            hub.publish(&img, (4, 2), |s| s.iteration = i);
        }
        let (seq, json) = hub.wait_newer(0, Duration::from_millis(10)).unwrap();
        assert!(json.contains("\"iteration\":3"), "{json}");
        let (image_seq, bytes) = hub.frame().unwrap();
        assert_eq!(image_seq, seq);
        assert!(json.contains(&format!("\"image\":{image_seq}")), "{json}");
        // Header: 2x1 shown at 4x2; then the first pixel's red is the third image's.
        let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
        assert_eq!([word(0), word(1), word(2), word(3)], [2, 1, 4, 2]);
        assert_eq!(f32::from_le_bytes(bytes[16..20].try_into().unwrap()), 3.0);
        assert_eq!(bytes.len(), 16 + 2 * 12);
        // Nothing newer: the reader waits (then sends a keep-alive).
        assert!(hub.wait_newer(seq, Duration::from_millis(10)).is_none());
    }

    /// A request declaring a huge body (which `tiny_http` would allocate at once to skip) does
    /// not take the server down: the page is still served after it.
    #[test]
    fn a_request_with_a_huge_declared_body_is_left_alone() {
        use std::io::Read;
        let server = Server::start(0, Hub::new("s.scn".into())).unwrap();
        let addr = server
            .url
            .trim_start_matches("http://")
            .trim_end_matches('/');
        let mut hostile = std::net::TcpStream::connect(addr).unwrap();
        hostile
            .write_all(b"GET / HTTP/1.1\r\nHost: x\r\nContent-Length: 99999999999\r\n\r\n")
            .unwrap();
        std::thread::sleep(Duration::from_millis(100));
        drop(hostile);
        let mut ok = std::net::TcpStream::connect(addr).unwrap();
        ok.write_all(b"GET / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
            .unwrap();
        let mut text = String::new();
        ok.read_to_string(&mut text).unwrap();
        assert!(text.starts_with("HTTP/1.1 200"), "{text:.80}");
    }

    #[test]
    fn a_port_in_use_is_a_clear_error() {
        let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = taken.local_addr().unwrap().port();
        let Err(e) = Server::start(port, Hub::new("s.scn".into())) else {
            panic!("bound a port in use");
        };
        assert!(
            e.contains("the port is in use") && e.contains("--port"),
            "{e}"
        );
    }
}
