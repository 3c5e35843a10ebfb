//! The protocol's framing over stdin and stdout (`Content-Length` headers, then JSON), on a
//! reader and a writer thread. Unlike `lsp_server::Connection::stdio` it survives a client's
//! junk: a malformed header or body is skipped with a note on stderr (a request whose id can
//! be read gets an error response), and a body larger than [`MAX_MESSAGE`] is read past
//! without being held.

use std::io::{self, BufRead, Read, Write};

use crossbeam_channel::{Sender, bounded, unbounded};
use lsp_server::{Connection, ErrorCode, Message, RequestId, Response};

/// The largest message read: a document of the largest scene file the load accepts, written as
/// JSON with every byte escaped, would be larger; 512 MiB holds any file an editor shows.
pub const MAX_MESSAGE: usize = 512 << 20;
/// The longest header line kept (longer ones are junk).
const MAX_HEADER_LINE: usize = 8 << 10;

/// The threads that move messages; joined when the server ends.
pub struct IoThreads {
    reader: std::thread::JoinHandle<()>,
    writer: std::thread::JoinHandle<()>,
}

impl IoThreads {
    /// Waits for the writer to send what is queued (the reader may be blocked on a stdin the
    /// client keeps open: it is left to end with the process).
    pub fn join(self) {
        let _ = self.writer.join();
        drop(self.reader);
    }
}

/// A connection over stdin and stdout.
pub fn stdio() -> (Connection, IoThreads) {
    let (to_writer, from_server) = unbounded::<Message>();
    let (to_server, from_reader) = bounded::<Message>(16);
    let replies = to_writer.clone();
    let writer = std::thread::Builder::new()
        .name("lsp-writer".into())
        .spawn(move || {
            let stdout = io::stdout();
            let mut out = stdout.lock();
            for m in from_server {
                if m.write(&mut out).and_then(|()| out.flush()).is_err() {
                    break;
                }
            }
        })
        .expect("a thread for the writer");
    let reader = std::thread::Builder::new()
        .name("lsp-reader".into())
        .spawn(move || {
            let stdin = io::stdin();
            read_all(&mut stdin.lock(), &to_server, &replies);
        })
        .expect("a thread for the reader");
    (
        Connection {
            sender: to_writer,
            receiver: from_reader,
        },
        IoThreads { reader, writer },
    )
}

/// Reads messages from `input` until it ends (or the server stops listening), passing each
/// to `server`; a request that cannot be read gets its error response through `replies`.
pub fn read_all(input: &mut impl BufRead, server: &Sender<Message>, replies: &Sender<Message>) {
    loop {
        let body = match read_body(input) {
            Ok(Some(b)) => b,
            Ok(None) => return,
            Err(e) => {
                say!("sppm-lang lsp: {e}");
                continue;
            }
        };
        match serde_json::from_slice::<Message>(&body) {
            Ok(m) => {
                let exit = matches!(&m, Message::Notification(n) if n.method == "exit");
                if server.send(m).is_err() || exit {
                    return;
                }
            }
            Err(e) => {
                say!("sppm-lang lsp: a message that is not JSON-RPC was skipped ({e})");
                if let Some(id) = request_id(&body) {
                    let r = Response::new_err(
                        id,
                        ErrorCode::InvalidRequest as i32,
                        format!("not a request: {e}"),
                    );
                    let _ = replies.send(r.into());
                }
            }
        }
    }
}

/// The id of a JSON object that has one, when the rest of it is not a message.
fn request_id(body: &[u8]) -> Option<RequestId> {
    let v: serde_json::Value = serde_json::from_slice(body).ok()?;
    match v.get("id")? {
        serde_json::Value::Number(n) => n
            .as_i64()
            .and_then(|n| i32::try_from(n).ok())
            .map(RequestId::from),
        serde_json::Value::String(s) => Some(RequestId::from(s.clone())),
        _ => None,
    }
}

/// One line of at most [`MAX_HEADER_LINE`] bytes (the rest of a longer one is skipped), without
/// its line break; `None` at the end of the input.
fn header_line(input: &mut impl BufRead) -> io::Result<Option<Vec<u8>>> {
    let mut line = Vec::new();
    let n = input
        .by_ref()
        .take(MAX_HEADER_LINE as u64)
        .read_until(b'\n', &mut line)?;
    if n == 0 {
        return Ok(None);
    }
    if !line.ends_with(b"\n") && n == MAX_HEADER_LINE {
        // Skip to the line's end.
        let mut rest = Vec::new();
        loop {
            rest.clear();
            let k = input
                .by_ref()
                .take(MAX_HEADER_LINE as u64)
                .read_until(b'\n', &mut rest)?;
            if k == 0 || rest.ends_with(b"\n") {
                break;
            }
        }
        return Ok(Some(b"(junk)".to_vec()));
    }
    while matches!(line.last(), Some(b'\n' | b'\r')) {
        line.pop();
    }
    Ok(Some(line))
}

/// The body of the next message: headers up to an empty line, then `Content-Length` bytes.
/// Lines before a `Content-Length` header that are not headers are skipped; `Ok(None)` at the
/// end of the input, an error for a body that is skipped.
fn read_body(input: &mut impl BufRead) -> io::Result<Option<Vec<u8>>> {
    let mut length: Option<usize> = None;
    loop {
        let Some(line) = header_line(input)? else {
            return Ok(None);
        };
        if line.is_empty() {
            if length.is_some() {
                break;
            }
            continue;
        }
        let text = String::from_utf8_lossy(&line);
        if let Some((name, value)) = text.split_once(':')
            && name.trim().eq_ignore_ascii_case("content-length")
        {
            length = value.trim().parse().ok();
            if length.is_none() {
                return Err(io::Error::other(format!(
                    "a Content-Length that is not a number: {}",
                    value.trim()
                )));
            }
        }
    }
    let n = length.unwrap_or(0);
    if n > MAX_MESSAGE {
        io::copy(&mut input.by_ref().take(n as u64), &mut io::sink())?;
        return Err(io::Error::other(format!(
            "a message of {n} bytes, more than the limit of {MAX_MESSAGE}, was skipped"
        )));
    }
    let mut body = Vec::new();
    input.by_ref().take(n as u64).read_to_end(&mut body)?;
    if body.len() < n {
        return Ok(None);
    }
    Ok(Some(body))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(body: &str) -> String {
        format!("Content-Length: {}\r\n\r\n{body}", body.len())
    }

    #[test]
    fn junk_is_skipped_and_the_next_message_read() {
        let good = r#"{"jsonrpc":"2.0","method":"initialized","params":{}}"#;
        let input = format!(
            "garbage line\r\n{}{}{}Content-Length: 99999999999\r\n\r\n{}",
            frame("{not json"),
            frame(r#"{"jsonrpc":"2.0","id":7,"method":5}"#),
            frame(good),
            frame(good),
        );
        let (tx, rx) = unbounded();
        let (rtx, rrx) = unbounded();
        read_all(&mut io::Cursor::new(input.into_bytes()), &tx, &rtx);
        let got: Vec<Message> = rx.try_iter().collect();
        // The oversized one swallowed the rest of the input as its body: one message read.
        assert_eq!(got.len(), 1, "{got:?}");
        let replies: Vec<Message> = rrx.try_iter().collect();
        assert!(
            matches!(&replies[..], [Message::Response(r)] if r.id == RequestId::from(7)),
            "{replies:?}"
        );
    }
}
