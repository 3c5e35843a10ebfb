//! Who may use the live view: the checks every request passes before it is answered.
//!
//! - `Host` must name this server as the browser reached it: `127.0.0.1`, `localhost` or
//!   `[::1]` with the port. A page on another site whose name an attacker re-points at
//!   127.0.0.1 (DNS rebinding) sends its own name and is refused.
//! - `Origin`, when the browser sends one (cross-origin requests, event streams opened by
//!   other sites), must be one of those same three origins.
//! - The token: a random secret printed in the URL (as Jupyter does). A request carries it as
//!   `?token=` or as the cookie set when the page was first opened with it, so other local
//!   users of a shared machine, who can reach the port but cannot read the terminal, are
//!   refused. `--no-token` turns this check off.

use std::fmt::Write;

/// What a request must show to be answered.
#[derive(Debug, Clone)]
pub struct Access {
    port: u16,
    /// `None`: `--no-token`.
    token: Option<String>,
}

/// Why a request is refused (all answered 403).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    Host,
    Origin,
    Token,
}

impl Refusal {
    /// The text of the 403 answer.
    pub fn message(self) -> &'static str {
        match self {
            Refusal::Host => "forbidden: the Host header does not name this local server\n",
            Refusal::Origin => "forbidden: requests from other sites are not answered\n",
            Refusal::Token => {
                "forbidden: open the URL that `sppm-lang watch --serve` printed (it carries the \
                 access token)\n"
            }
        }
    }
}

/// How a request proved the token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Granted {
    /// By the cookie, or no token is required.
    Cookie,
    /// By `?token=` in the URL: the answer sets the cookie.
    Query,
}

impl Access {
    /// Access for the server on `port`; with a token unless `token` is `None`.
    pub fn new(port: u16, token: Option<String>) -> Self {
        Self { port, token }
    }

    /// A fresh random token: 128 bits from the operating system, as hexadecimal.
    pub fn random_token() -> Result<String, String> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes)
            .map_err(|e| format!("cannot make the live view's access token: {e}"))?;
        let mut text = String::with_capacity(32);
        for b in bytes {
            let _ = write!(text, "{b:02x}");
        }
        Ok(text)
    }

    /// The URL to print: the page, with the token when one is required.
    pub fn url(&self) -> String {
        match &self.token {
            Some(t) => format!("http://127.0.0.1:{}/?token={t}", self.port),
            None => format!("http://127.0.0.1:{}/", self.port),
        }
    }

    /// The cookie's name: one per port, since browsers share cookies between the ports of a
    /// host (two `watch --serve` at once each keep their own).
    pub fn cookie_name(&self) -> String {
        format!("sppm_lang_{}", self.port)
    }

    /// The `Set-Cookie` value for a request that showed the token in its URL.
    pub fn set_cookie(&self) -> Option<String> {
        self.token
            .as_ref()
            .map(|t| format!("{}={t}; Path=/; HttpOnly; SameSite=Lax", self.cookie_name()))
    }

    /// Checks a request's `Host`, `Origin`, query and `Cookie` headers (each `None` when
    /// absent; a header sent twice is refused by the caller).
    pub fn check(
        &self,
        host: Option<&[u8]>,
        origin: Option<&[u8]>,
        query: Option<&str>,
        cookies: &[&[u8]],
    ) -> Result<Granted, Refusal> {
        if !host.is_some_and(|h| self.is_local_authority(h)) {
            return Err(Refusal::Host);
        }
        if let Some(o) = origin {
            let local = o
                .strip_prefix(b"http://")
                .is_some_and(|a| self.is_local_authority(a));
            if !local {
                return Err(Refusal::Origin);
            }
        }
        let Some(token) = &self.token else {
            return Ok(Granted::Cookie);
        };
        let name = self.cookie_name();
        let by_cookie = cookies
            .iter()
            .flat_map(|header| header.split(|&b| b == b';'))
            .filter_map(|pair| {
                let pair = pair.trim_ascii();
                let eq = pair.iter().position(|&b| b == b'=')?;
                (pair[..eq] == *name.as_bytes()).then(|| &pair[eq + 1..])
            })
            .any(|value| same(value, token.as_bytes()));
        if by_cookie {
            return Ok(Granted::Cookie);
        }
        let by_query = query
            .into_iter()
            .flat_map(|q| q.split('&'))
            .filter_map(|pair| pair.strip_prefix("token="))
            .any(|value| same(value.as_bytes(), token.as_bytes()));
        if by_query {
            Ok(Granted::Query)
        } else {
            Err(Refusal::Token)
        }
    }

    /// `host[:port]` names this server: a loopback name and this port (a browser leaves out
    /// port 80).
    fn is_local_authority(&self, authority: &[u8]) -> bool {
        let Ok(text) = std::str::from_utf8(authority) else {
            return false;
        };
        let (name, port) = match text.rsplit_once(':') {
            // `[::1]` alone has colons inside its brackets.
            Some((name, port)) if !port.contains(']') => (name, Some(port)),
            _ => (text, None),
        };
        let port_ok = match port {
            Some(p) => p.parse::<u16>().is_ok_and(|p| p == self.port) && !p.starts_with('+'),
            None => self.port == 80,
        };
        port_ok
            && (name == "127.0.0.1" || name == "[::1]" || name.eq_ignore_ascii_case("localhost"))
    }
}

/// Compares a presented secret with the token in time that does not depend on where they
/// differ.
fn same(presented: &[u8], token: &[u8]) -> bool {
    if presented.len() != token.len() {
        return false;
    }
    presented
        .iter()
        .zip(token)
        .fold(0u8, |acc, (a, b)| acc | (a ^ b))
        == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn access() -> Access {
        Access::new(8421, Some("abc123".into()))
    }

    #[test]
    fn only_loopback_names_with_the_port_are_this_server() {
        let a = access();
        for ok in [
            "127.0.0.1:8421",
            "localhost:8421",
            "LocalHost:8421",
            "[::1]:8421",
        ] {
            assert!(a.is_local_authority(ok.as_bytes()), "{ok}");
        }
        for bad in [
            "127.0.0.1",
            "127.0.0.1:8422",
            "127.0.0.1:+8421",
            "evil.example:8421",
            "localhost.evil.example:8421",
            "127.0.0.2:8421",
            "[::1]",
            "",
            "127.0.0.1:8421:8421",
        ] {
            assert!(!a.is_local_authority(bad.as_bytes()), "{bad}");
        }
        assert!(Access::new(80, None).is_local_authority(b"localhost"));
    }

    #[test]
    fn a_foreign_host_or_origin_is_refused_even_with_the_token() {
        let a = access();
        let q = Some("token=abc123");
        assert_eq!(
            a.check(Some(b"rebound.example:8421"), None, q, &[]),
            Err(Refusal::Host)
        );
        assert_eq!(a.check(None, None, q, &[]), Err(Refusal::Host));
        assert_eq!(
            a.check(
                Some(b"127.0.0.1:8421"),
                Some(b"http://evil.example"),
                q,
                &[]
            ),
            Err(Refusal::Origin)
        );
        // `null` (a sandboxed frame or a file:// page) is not this server either.
        assert_eq!(
            a.check(Some(b"127.0.0.1:8421"), Some(b"null"), q, &[]),
            Err(Refusal::Origin)
        );
        assert_eq!(
            a.check(
                Some(b"127.0.0.1:8421"),
                Some(b"http://localhost:8421"),
                q,
                &[]
            ),
            Ok(Granted::Query)
        );
    }

    #[test]
    fn the_token_comes_by_query_or_by_this_ports_cookie() {
        let a = access();
        let host = Some(&b"127.0.0.1:8421"[..]);
        assert_eq!(a.check(host, None, None, &[]), Err(Refusal::Token));
        assert_eq!(
            a.check(host, None, Some("x=1&token=abc123"), &[]),
            Ok(Granted::Query)
        );
        assert_eq!(
            a.check(host, None, Some("token=abc124"), &[]),
            Err(Refusal::Token)
        );
        assert_eq!(
            a.check(host, None, Some("token=abc1234"), &[]),
            Err(Refusal::Token)
        );
        assert_eq!(
            a.check(host, None, None, &[b"a=b; sppm_lang_8421=abc123"]),
            Ok(Granted::Cookie)
        );
        // Another port's cookie is another server's.
        assert_eq!(
            a.check(host, None, None, &[b"sppm_lang_8422=abc123"]),
            Err(Refusal::Token)
        );
        let open = Access::new(8421, None);
        assert_eq!(open.check(host, None, None, &[]), Ok(Granted::Cookie));
        assert!(open.set_cookie().is_none());
    }

    #[test]
    fn tokens_are_random_and_long() {
        let (a, b) = (
            Access::random_token().unwrap(),
            Access::random_token().unwrap(),
        );
        assert_eq!(a.len(), 32);
        assert_ne!(a, b);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
    }
}
