//! `watch --serve`: a local web page that shows the render as it progresses.
//!
//! The watch loop and its render thread publish into a [`Hub`]: the latest status (what runs,
//! iteration, photons/s, diagnostics) and the latest image, linear RGB. Nothing is queued: a
//! newer status or image replaces the older one, so a slow or closed browser tab never makes
//! anything grow. The HTTP side ([`Server`], hyper on a small tokio runtime, see [`http`] for
//! its limits and [`access`] for who gets in) serves
//!
//! - `/`: the page (static HTML and JavaScript built into the binary);
//! - `/events`: server-sent events, one `data:` line of JSON per status change (a tab that
//!   misses some sees the latest), and a comment every few seconds so that a closed tab is
//!   noticed;
//! - `/image`: the latest image as 16 bytes of header (width, height, full width, full height,
//!   u32 little-endian) and then `width * height * 3` linear f32 values, row 0 at the top. A
//!   preview is smaller than the full size; the page draws it scaled up to the full size.
//!
//! The page tone-maps the linear image itself (exposure slider, sRGB curve) and reads out the
//! linear value under the cursor.

mod access;
mod http;
mod stall;
mod view;

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use bytes::Bytes;
use sppm_lang::Image;

pub use access::Access;
pub use view::{DiagnosticView, diagnostics_view};

/// The page, built into the binary.
const PAGE: &str = include_str!("page.html");

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
    bytes: Bytes,
}

struct State {
    seq: u64,
    status: Status,
    frame: Option<Frame>,
    /// The status as an event-stream message, made once per change for every tab.
    message: Option<(u64, Bytes)>,
}

/// The latest status and image, shared by the watch loop and the page's connections.
pub struct Hub {
    state: Mutex<State>,
    /// The latest sequence number, for the event streams to wait on.
    changed: tokio::sync::watch::Sender<u64>,
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
                message: None,
            }),
            changed: tokio::sync::watch::Sender::new(1),
        })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic elsewhere while holding the lock leaves plain data: keep serving it.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Changes the status and wakes every event stream.
    pub fn update(&self, change: impl FnOnce(&mut Status)) {
        let seq = {
            let mut s = self.lock();
            change(&mut s.status);
            s.seq += 1;
            s.seq
        };
        self.changed.send_replace(seq);
    }

    /// Replaces the image (shown at `full` size) and changes the status in one step.
    pub fn publish(&self, image: &Image, full: (u32, u32), change: impl FnOnce(&mut Status)) {
        let bytes = Bytes::from(encode(image, full));
        let seq = {
            let mut s = self.lock();
            let seq = s.seq + 1;
            s.frame = Some(Frame { seq, bytes });
            change(&mut s.status);
            s.seq = seq;
            seq
        };
        self.changed.send_replace(seq);
    }

    /// A receiver that wakes at every change.
    fn subscribe(&self) -> tokio::sync::watch::Receiver<u64> {
        self.changed.subscribe()
    }

    /// The latest status as an event-stream message (`data: {json}`), with its sequence number.
    fn event(&self) -> (u64, Bytes) {
        let mut s = self.lock();
        if let Some((seq, message)) = &s.message
            && *seq == s.seq
        {
            return (*seq, message.clone());
        }
        let image = s.frame.as_ref().map_or(0, |f| f.seq);
        let message = Bytes::from(format!("data: {}\n\n", view::status_json(&s.status, image)));
        s.message = Some((s.seq, message.clone()));
        (s.seq, message)
    }

    fn frame(&self) -> Option<(u64, Bytes)> {
        self.lock().frame.as_ref().map(|f| (f.seq, f.bytes.clone()))
    }
}

/// Memory the live view may hold for an image of `width` x `height` pixels, beside the render:
/// the hub's image, the one being encoded, one per image answer in flight, and every
/// connection's buffers and event-stream message.
pub fn reserved_memory(width: u32, height: u32) -> u64 {
    let frame = (u64::from(width) * u64::from(height))
        .saturating_mul(12)
        .saturating_add(16);
    let frames = (2 + http::MAX_IMAGE_SENDS as u64).saturating_mul(frame);
    let connections = http::MAX_CONNECTIONS as u64 * http::PER_CONNECTION
        + http::MAX_STREAMS as u64 * view::MAX_STATUS_BYTES;
    frames.saturating_add(connections)
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
    /// The URL to open (with the token, when one is required).
    pub url: String,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0: any free port) and serves `hub`; `token`: whether a
    /// request must show the random token of this run (`--no-token` turns it off).
    pub fn start(port: u16, token: bool, hub: Arc<Hub>) -> Result<Server, String> {
        let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
        let listener = std::net::TcpListener::bind(addr).map_err(|e| {
            if e.kind() == std::io::ErrorKind::AddrInUse {
                format!(
                    "cannot serve the page on {addr}: the port is in use (another program, or \
                     another `watch --serve`); choose another with --port, or --port 0 for any \
                     free port"
                )
            } else {
                format!("cannot serve the page on {addr}: {e}")
            }
        })?;
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("cannot serve the page on {addr}: {e}"))?;
        let bound = listener.local_addr().map_or(port, |a| a.port());
        let token = if token {
            Some(Access::random_token()?)
        } else {
            None
        };
        let access = Access::new(bound, token);
        let url = access.url();
        std::thread::Builder::new()
            .name("live-server".into())
            .spawn(move || http::serve(listener, hub, access))
            .map_err(|e| format!("cannot start the page's server thread: {e}"))?;
        Ok(Server { url })
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
        let mut changes = hub.subscribe();
        for i in 1..=3u32 {
            let mut img = Image::new(2, 1);
            img.pixels[0] = [f64::from(i), 0.0, 0.0];
            hub.publish(&img, (4, 2), |s| s.iteration = i);
        }
        assert!(changes.has_changed().unwrap());
        assert_eq!(*changes.borrow_and_update(), 4);
        let (seq, message) = hub.event();
        let text = std::str::from_utf8(&message).unwrap();
        assert!(
            text.starts_with("data: {") && text.ends_with("}\n\n"),
            "{text}"
        );
        assert!(text.contains("\"iteration\":3"), "{text}");
        let (image_seq, bytes) = hub.frame().unwrap();
        assert_eq!(image_seq, seq);
        assert!(text.contains(&format!("\"image\":{image_seq}")), "{text}");
        // Header: 2x1 shown at 4x2; then the first pixel's red is the third image's.
        let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
        assert_eq!([word(0), word(1), word(2), word(3)], [2, 1, 4, 2]);
        assert_eq!(f32::from_le_bytes(bytes[16..20].try_into().unwrap()), 3.0);
        assert_eq!(bytes.len(), 16 + 2 * 12);
        // The message is made once per change and shared.
        let (_, again) = hub.event();
        assert_eq!(again.as_ptr(), message.as_ptr());
        assert!(!changes.has_changed().unwrap());
    }

    #[test]
    fn a_port_in_use_is_a_clear_error() {
        let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = taken.local_addr().unwrap().port();
        let Err(e) = Server::start(port, true, Hub::new("s.scn".into())) else {
            panic!("bound a port in use");
        };
        assert!(
            e.contains("the port is in use") && e.contains("--port"),
            "{e}"
        );
    }

    #[test]
    fn the_reserve_counts_every_image_copy() {
        let small = reserved_memory(1, 1);
        let big = reserved_memory(1000, 1000);
        assert_eq!(
            big - small,
            (2 + http::MAX_IMAGE_SENDS as u64) * 12 * (1_000_000 - 1)
        );
        assert_eq!(reserved_memory(u32::MAX, u32::MAX), u64::MAX);
    }
}
