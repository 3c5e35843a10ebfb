//! A forgiving tokenizer: words, numbers, strings, comments, `#` directives and punctuation
//! with their byte ranges. Unlike the grammar it never fails, so a half-typed file still has
//! its names, blocks and braces for completion, hover and the outline.

use std::ops::Range;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A name or keyword: a letter or `_`, then letters, digits and `_`.
    Word,
    Number,
    /// A string; `closed` is false when the line (or the text) ended first.
    Str {
        closed: bool,
    },
    /// A line or block comment (a block comment left open runs to the end).
    Comment,
    /// `#` and the word after it (`#declare`); a `#` alone is punctuation.
    Directive,
    /// One other character (ASCII or not).
    Punct,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Token {
    pub kind: Kind,
    pub start: usize,
    pub end: usize,
}

impl Token {
    pub fn range(&self) -> Range<usize> {
        self.start..self.end
    }

    pub fn text<'a>(&self, text: &'a str) -> &'a str {
        &text[self.start..self.end]
    }

    pub fn is_punct(&self, text: &str, c: char) -> bool {
        self.kind == Kind::Punct && text[self.start..].starts_with(c)
    }

    /// Whether the token is `#word` (`word` without the `#`).
    pub fn is_directive(&self, text: &str, word: &str) -> bool {
        self.kind == Kind::Directive && &text[self.start + 1..self.end] == word
    }

    /// A string's contents, without its quotes.
    pub fn inner<'a>(&self, text: &'a str) -> &'a str {
        let closed = matches!(self.kind, Kind::Str { closed: true });
        let end = if closed { self.end - 1 } else { self.end };
        &text[(self.start + 1).min(end)..end]
    }
}

fn word_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The tokens of `text`, comments included, white space left out.
pub fn tokens(text: &str) -> Vec<Token> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        let kind = if c.is_ascii_whitespace() {
            i += 1;
            continue;
        } else if c == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && bytes[i] != b'\n' && bytes[i] != b'\r' {
                i += 1;
            }
            Kind::Comment
        } else if c == b'/' && bytes.get(i + 1) == Some(&b'*') {
            // Block comments nest, as in the grammar.
            let mut depth = 0usize;
            while i < bytes.len() {
                if bytes[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if bytes[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            Kind::Comment
        } else if c == b'"' {
            i += 1;
            let mut closed = false;
            while i < bytes.len() {
                match bytes[i] {
                    b'\\' if i + 1 < bytes.len() && bytes[i + 1] != b'\n' => i += 2,
                    b'"' => {
                        i += 1;
                        closed = true;
                        break;
                    }
                    b'\n' | b'\r' => break,
                    _ => i += 1,
                }
            }
            Kind::Str { closed }
        } else if c == b'#' && bytes.get(i + 1).is_some_and(|b| b.is_ascii_alphabetic()) {
            i += 1;
            while i < bytes.len() && word_char(bytes[i]) {
                i += 1;
            }
            Kind::Directive
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while i < bytes.len() && word_char(bytes[i]) {
                i += 1;
            }
            Kind::Word
        } else if c.is_ascii_digit()
            || (c == b'.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                let mut j = i + 1;
                if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                    j += 1;
                }
                if j < bytes.len() && bytes[j].is_ascii_digit() {
                    i = j;
                    while i < bytes.len() && bytes[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            Kind::Number
        } else {
            // One character, whole (the text is UTF-8).
            i += text[i..].chars().next().map_or(1, char::len_utf8);
            Kind::Punct
        };
        // A string or comment that ran into a multi-byte character stopped on a boundary.
        while !text.is_char_boundary(i) {
            i += 1;
        }
        out.push(Token {
            kind,
            start,
            end: i.min(bytes.len()),
        });
    }
    out
}

/// The index of the token that holds byte `offset` or ends at it (the word being typed when
/// the cursor stands right after it), else `None`.
pub fn at(tokens: &[Token], offset: usize) -> Option<usize> {
    let i = tokens.partition_point(|t| t.end < offset);
    (i < tokens.len() && tokens[i].start <= offset).then_some(i)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<(Kind, &str)> {
        tokens(text)
            .iter()
            .map(|t| (t.kind, t.text(text)))
            .collect()
    }

    #[test]
    fn every_kind_with_its_text() {
        let text =
            "#declare R_1 = 1.5e-3; // note\nsphere { <0,.5,0>, \"a\\\"b\" } /* x /* y */ z */ é #";
        let k = kinds(text);
        assert_eq!(k[0], (Kind::Directive, "#declare"));
        assert_eq!(k[1], (Kind::Word, "R_1"));
        assert_eq!(k[3], (Kind::Number, "1.5e-3"));
        assert_eq!(k[5], (Kind::Comment, "// note"));
        assert!(k.contains(&(Kind::Number, ".5")));
        assert!(k.contains(&(Kind::Str { closed: true }, "\"a\\\"b\"")));
        assert!(k.contains(&(Kind::Comment, "/* x /* y */ z */")));
        assert!(k.contains(&(Kind::Punct, "é")));
        assert_eq!(k.last(), Some(&(Kind::Punct, "#")));
    }

    #[test]
    fn unfinished_strings_and_comments_stop_where_they_must() {
        let text = "#include \"parts/\nbox /* open";
        let t = tokens(text);
        assert_eq!(t[1].kind, Kind::Str { closed: false });
        assert_eq!(t[1].inner(text), "parts/");
        assert_eq!(t[2].text(text), "box");
        assert_eq!(t[3].kind, Kind::Comment);
        assert_eq!(t[3].end, text.len());
        assert_eq!(at(&t, text.find("box").unwrap() + 3), Some(2));
    }
}
