//! The live view's HTTP server: hyper's HTTP/1 on a single-threaded tokio runtime of its own,
//! with every limit enforced here rather than trusted to the clients.
//!
//! - Only `GET` and `HEAD` (405 otherwise), no request bodies (400), a request line and headers
//!   of at most [`MAX_HEAD`] bytes (hyper answers 431 or 414 and closes), the head within
//!   [`HEAD_TIMEOUT`], and a write that makes no progress for
//!   [`super::stall::WRITE_STALL`] closes its connection.
//! - Every request first passes [`Access`]: `Host`, `Origin`, token (403 otherwise).
//! - At most [`MAX_CONNECTIONS`] connections, [`MAX_STREAMS`] of them event streams and
//!   [`MAX_IMAGE_SENDS`] of them sending an image; past these a client gets 503 and the others
//!   go on. An error accepting a connection (the open-file limit) is said once and the server
//!   keeps accepting once descriptors are free again.
//! - Each connection is a task of its own: a client that stops reading holds its own
//!   connection and nothing else.

use std::convert::Infallible;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::task::{Context, Poll};
use std::time::Duration;

use bytes::Bytes;
use http_body_util::BodyExt;
use http_body_util::combinators::BoxBody;
use hyper::body::{Frame, Incoming, SizeHint};
use hyper::header::{self, HeaderMap, HeaderName, HeaderValue};
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use super::access::{Access, Granted};
use super::stall::{StallLimit, WRITE_STALL};
use super::{Hub, PAGE};

/// Most connections open at once.
pub const MAX_CONNECTIONS: usize = 128;
/// Most event streams (browser tabs) at once.
pub const MAX_STREAMS: usize = 32;
/// Most image answers in flight at once (each holds one image until it is sent).
pub const MAX_IMAGE_SENDS: usize = 4;
/// Longest request line plus headers, and the most a connection buffers either way.
pub const MAX_HEAD: usize = 16 * 1024;
/// Longest wait for a request's head once a connection is open or idle.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// An image answer is handed to the connection in copies of this size, so that a client that
/// stops reading keeps at most one piece (not the image) once its answer's slot is given back.
pub const IMAGE_CHUNK: usize = 64 * 1024;
/// How often an idle event stream sends a comment (finds closed tabs, keeps proxies open).
const KEEP_ALIVE: Duration = Duration::from_secs(5);
/// Most bytes one connection holds at once besides a shared image or status: hyper's read and
/// write buffers and one image piece.
pub const PER_CONNECTION: u64 = (2 * MAX_HEAD + IMAGE_CHUNK) as u64;

type Body = BoxBody<Bytes, Infallible>;

/// What every connection shares.
struct Shared {
    hub: Arc<Hub>,
    access: Access,
    connections: Arc<Semaphore>,
    streams: Arc<Semaphore>,
    images: Arc<Semaphore>,
    said_accept_error: AtomicBool,
    said_busy: AtomicBool,
}

/// Serves `hub` on `listener` until the process ends (run on a thread of its own).
pub fn serve(listener: std::net::TcpListener, hub: Arc<Hub>, access: Access) {
    let runtime = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            say(&format!("live view: cannot start its server: {e}"));
            return;
        }
    };
    let shared = Arc::new(Shared {
        hub,
        access,
        connections: Arc::new(Semaphore::new(MAX_CONNECTIONS)),
        streams: Arc::new(Semaphore::new(MAX_STREAMS)),
        images: Arc::new(Semaphore::new(MAX_IMAGE_SENDS)),
        said_accept_error: AtomicBool::new(false),
        said_busy: AtomicBool::new(false),
    });
    runtime.block_on(async move {
        let listener = match TcpListener::from_std(listener) {
            Ok(l) => l,
            Err(e) => {
                say(&format!("live view: cannot listen: {e}"));
                return;
            }
        };
        accept(listener, shared).await;
    });
}

async fn accept(listener: TcpListener, shared: Arc<Shared>) {
    loop {
        match listener.accept().await {
            Ok((stream, _)) => match shared.connections.clone().try_acquire_owned() {
                Ok(permit) => {
                    tokio::spawn(connection(stream, shared.clone(), permit));
                }
                Err(_) => {
                    if !shared.said_busy.swap(true, Ordering::Relaxed) {
                        say(&format!(
                            "live view: {MAX_CONNECTIONS} connections are open; further ones \
                             are refused until some close (said once)"
                        ));
                    }
                    refuse(&stream);
                }
            },
            Err(e) => {
                // Out of file descriptors (or another passing failure): the connection waits
                // in the backlog; try again shortly.
                if !shared.said_accept_error.swap(true, Ordering::Relaxed) {
                    say(&format!(
                        "live view: cannot accept a connection ({e}); retrying (said once)"
                    ));
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        }
    }
}

/// A best-effort 503 to a connection over the cap, which is then closed.
fn refuse(stream: &TcpStream) {
    let _ = stream.try_write(
        b"HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\nContent-Length: 0\r\n\r\n",
    );
}

async fn connection(stream: TcpStream, shared: Arc<Shared>, _slot: OwnedSemaphorePermit) {
    let _ = stream.set_nodelay(true);
    let io = TokioIo::new(StallLimit::new(stream, WRITE_STALL));
    let service = hyper::service::service_fn(move |request| {
        let shared = shared.clone();
        async move { Ok::<_, Infallible>(answer(&shared, &request)) }
    });
    // An error here is the client's (gone, too slow, malformed): its connection ends.
    let _ = hyper::server::conn::http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(HEAD_TIMEOUT)
        .max_buf_size(MAX_HEAD)
        .serve_connection(io, service)
        .await;
}

fn answer(shared: &Shared, request: &Request<Incoming>) -> Response<Body> {
    let head = request.method() == Method::HEAD;
    if request.method() != Method::GET && !head {
        let mut r = plain(
            StatusCode::METHOD_NOT_ALLOWED,
            "only GET and HEAD are answered\n",
        );
        r.headers_mut()
            .insert(header::ALLOW, HeaderValue::from_static("GET, HEAD"));
        return closing(r);
    }
    if has_body(request.headers()) {
        return closing(plain(
            StatusCode::BAD_REQUEST,
            "requests to this server carry no body\n",
        ));
    }
    let headers = request.headers();
    let (Ok(host), Ok(origin)) = (one(headers, header::HOST), one(headers, header::ORIGIN)) else {
        return plain(StatusCode::BAD_REQUEST, "a header is repeated\n");
    };
    let cookies: Vec<&[u8]> = headers
        .get_all(header::COOKIE)
        .iter()
        .map(HeaderValue::as_bytes)
        .collect();
    let granted = match shared
        .access
        .check(host, origin, request.uri().query(), &cookies)
    {
        Ok(g) => g,
        Err(refusal) => return plain(StatusCode::FORBIDDEN, refusal.message()),
    };
    let mut response = route(shared, request.uri().path(), granted, head);
    if granted == Granted::Query
        && let Some(cookie) = shared.access.set_cookie()
        && let Ok(value) = HeaderValue::from_str(&cookie)
    {
        response.headers_mut().insert(header::SET_COOKIE, value);
    }
    if head {
        // The headers as for GET; no body (and no stream or image slot held).
        *response.body_mut() = empty();
    }
    response
}

fn route(shared: &Shared, path: &str, granted: Granted, head: bool) -> Response<Body> {
    match path {
        // The token leaves the address bar (and the history): the cookie carries it now.
        "/" | "/index.html" if granted == Granted::Query => {
            let mut r = plain(StatusCode::SEE_OTHER, "");
            r.headers_mut()
                .insert(header::LOCATION, HeaderValue::from_static("/"));
            r
        }
        "/" | "/index.html" => {
            let mut r = with_type(
                Response::new(full(Bytes::from_static(PAGE.as_bytes()))),
                "text/html; charset=utf-8",
            );
            let h = r.headers_mut();
            h.insert(
                header::CONTENT_SECURITY_POLICY,
                HeaderValue::from_static("frame-ancestors 'none'"),
            );
            h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
            r
        }
        "/image" => match shared.hub.frame() {
            None => status_only(StatusCode::NO_CONTENT),
            Some((seq, bytes)) => {
                let permit = if head {
                    None
                } else {
                    match shared.images.clone().try_acquire_owned() {
                        Ok(p) => Some(p),
                        Err(_) => return busy(),
                    }
                };
                let len = bytes.len();
                let body = Chunked {
                    data: bytes,
                    sent: 0,
                    _slot: permit,
                };
                let mut r = with_type(Response::new(body.boxed()), "application/octet-stream");
                let h = r.headers_mut();
                h.insert(header::CONTENT_LENGTH, HeaderValue::from(len));
                h.insert(
                    HeaderName::from_static("x-image-seq"),
                    HeaderValue::from(seq),
                );
                r
            }
        },
        "/events" => {
            if head {
                return with_type(Response::new(empty()), "text/event-stream");
            }
            match shared.streams.clone().try_acquire_owned() {
                Ok(permit) => with_type(
                    Response::new(events(shared.hub.clone(), permit)),
                    "text/event-stream",
                ),
                Err(_) => busy(),
            }
        }
        _ => plain(StatusCode::NOT_FOUND, "not found\n"),
    }
}

/// The value of a header that may appear once: `Err` when it appears more than once.
fn one(headers: &HeaderMap, name: HeaderName) -> Result<Option<&[u8]>, ()> {
    let mut values = headers.get_all(name).iter();
    let first = values.next().map(HeaderValue::as_bytes);
    if values.next().is_some() {
        Err(())
    } else {
        Ok(first)
    }
}

fn has_body(headers: &HeaderMap) -> bool {
    headers.contains_key(header::TRANSFER_ENCODING)
        || headers
            .get(header::CONTENT_LENGTH)
            .is_some_and(|v| v.as_bytes() != b"0")
}

/// The event stream: a `retry` line, then the status whenever it changes (a slow reader skips
/// to the latest) and a comment every [`KEEP_ALIVE`] when nothing changes.
fn events(hub: Arc<Hub>, slot: OwnedSemaphorePermit) -> Body {
    let changes = hub.subscribe();
    let start = Bytes::from_static(b"retry: 1000\n\n");
    let stream = futures_util::stream::unfold(
        (hub, changes, 0u64, slot, Some(start)),
        |(hub, mut changes, mut seen, slot, start)| async move {
            if let Some(first) = start {
                return Some((first, (hub, changes, seen, slot, None)));
            }
            loop {
                // Marked seen before the status is read: a change after this wakes the wait.
                changes.borrow_and_update();
                let (seq, message) = hub.event();
                if seq > seen {
                    seen = seq;
                    return Some((message, (hub, changes, seen, slot, None)));
                }
                match tokio::time::timeout(KEEP_ALIVE, changes.changed()).await {
                    Ok(Ok(())) => continue,
                    // The watch loop is gone: the stream ends.
                    Ok(Err(_)) => return None,
                    Err(_) => {
                        let alive = Bytes::from_static(b": alive\n\n");
                        return Some((alive, (hub, changes, seen, slot, None)));
                    }
                }
            }
        },
    );
    use futures_util::StreamExt;
    http_body_util::StreamBody::new(stream.map(|b| Ok(Frame::data(b)))).boxed()
}

/// An image answer: copies of [`IMAGE_CHUNK`] bytes, its slot held until the last is handed on.
struct Chunked {
    data: Bytes,
    sent: usize,
    _slot: Option<OwnedSemaphorePermit>,
}

impl hyper::body::Body for Chunked {
    type Data = Bytes;
    type Error = Infallible;

    fn poll_frame(
        mut self: Pin<&mut Self>,
        _: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, Infallible>>> {
        let (from, len) = (self.sent, self.data.len());
        if from >= len {
            return Poll::Ready(None);
        }
        let to = (from + IMAGE_CHUNK).min(len);
        self.sent = to;
        // A copy, not a slice: a slice would keep the whole image alive.
        let piece = Bytes::copy_from_slice(&self.data[from..to]);
        Poll::Ready(Some(Ok(Frame::data(piece))))
    }

    fn is_end_stream(&self) -> bool {
        self.sent >= self.data.len()
    }

    fn size_hint(&self) -> SizeHint {
        SizeHint::with_exact((self.data.len() - self.sent.min(self.data.len())) as u64)
    }
}

fn full(bytes: Bytes) -> Body {
    http_body_util::Full::new(bytes).boxed()
}

fn empty() -> Body {
    full(Bytes::new())
}

/// Headers every answer carries.
fn with_type(mut r: Response<Body>, content_type: &'static str) -> Response<Body> {
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    r
}

fn plain(status: StatusCode, text: &'static str) -> Response<Body> {
    let mut r = with_type(
        Response::new(full(Bytes::from_static(text.as_bytes()))),
        "text/plain; charset=utf-8",
    );
    *r.status_mut() = status;
    r
}

fn status_only(status: StatusCode) -> Response<Body> {
    let mut r = with_type(Response::new(empty()), "text/plain; charset=utf-8");
    *r.status_mut() = status;
    r
}

fn busy() -> Response<Body> {
    let mut r = plain(StatusCode::SERVICE_UNAVAILABLE, "busy, try again\n");
    r.headers_mut()
        .insert(header::RETRY_AFTER, HeaderValue::from_static("1"));
    r
}

fn closing(mut r: Response<Body>) -> Response<Body> {
    r.headers_mut()
        .insert(header::CONNECTION, HeaderValue::from_static("close"));
    r
}

fn say(message: &str) {
    eprintln!("[watch] {message}");
}
