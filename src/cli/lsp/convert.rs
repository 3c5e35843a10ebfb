//! Between the protocol's types and the library's: URIs and paths, positions, diagnostics,
//! completions and symbols.

use std::path::{Path, PathBuf};

use lsp_types as lsp;
use sppm_lang::Severity;
use sppm_lang::internals::ide;

/// The path a document's URI names: a `file:` URI's path (percent-decoded); for any other
/// scheme (an unsaved `untitled:` buffer), a path made of the URI under a folder that does not
/// exist, so that its includes resolve to nothing on disk.
pub fn path(uri: &lsp::Uri) -> PathBuf {
    let s = uri.as_str();
    let Some(rest) = s.strip_prefix("file://") else {
        return Path::new("/nonexistent-sppm-lsp-buffer")
            .join(percent_decode(&s.replace(['/', ':', '\\'], "_")));
    };
    // `file://localhost/p` and `file:///p`.
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    let decoded = percent_decode(rest);
    // Windows: `/C:/x` is `C:/x`.
    let b = decoded.as_bytes();
    if b.len() > 2 && b[0] == b'/' && b[2] == b':' && b[1].is_ascii_alphabetic() {
        return PathBuf::from(&decoded[1..]);
    }
    PathBuf::from(decoded)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%'
            && i + 2 < b.len()
            && let Ok(v) =
                u8::from_str_radix(std::str::from_utf8(&b[i + 1..i + 3]).unwrap_or("zz"), 16)
        {
            out.push(v);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A `file:` URI for `path`.
pub fn uri(path: &Path) -> Option<lsp::Uri> {
    let mut s = String::from("file://");
    let text = path.to_string_lossy().replace('\\', "/");
    if !text.starts_with('/') {
        s.push('/');
    }
    for &c in text.as_bytes() {
        if c.is_ascii_alphanumeric() || b"/-._~:".contains(&c) {
            s.push(c as char);
        } else {
            s.push_str(&format!("%{c:02X}"));
        }
    }
    s.parse().ok()
}

pub fn position(p: ide::Position) -> lsp::Position {
    lsp::Position::new(p.line, p.character)
}

pub fn from_position(p: lsp::Position) -> ide::Position {
    ide::Position {
        line: p.line,
        character: p.character,
    }
}

pub fn range(text: &str, index: &ide::LineIndex, r: std::ops::Range<usize>) -> lsp::Range {
    lsp::Range::new(
        position(index.position(text, r.start)),
        position(index.position(text, r.end)),
    )
}

pub fn diagnostic(d: &ide::FileDiagnostic) -> lsp::Diagnostic {
    lsp::Diagnostic {
        range: lsp::Range::new(position(d.start), position(d.end)),
        severity: Some(match d.severity {
            Severity::Error => lsp::DiagnosticSeverity::ERROR,
            Severity::Warning => lsp::DiagnosticSeverity::WARNING,
            Severity::Note => lsp::DiagnosticSeverity::INFORMATION,
        }),
        source: Some("sppm-lang".into()),
        message: d.message.clone(),
        ..Default::default()
    }
}

pub fn location(l: &ide::Location) -> Option<lsp::Location> {
    Some(lsp::Location::new(
        uri(&l.path)?,
        lsp::Range::new(position(l.start), position(l.end)),
    ))
}

/// A completion; `order` is its place in the list (the editor sorts by rank, then by it).
pub fn completion(c: &ide::Completion, order: usize, replace: lsp::Range) -> lsp::CompletionItem {
    use ide::CompletionKind as K;
    use lsp::CompletionItemKind as L;
    lsp::CompletionItem {
        label: c.label.clone(),
        kind: Some(match c.kind {
            K::Block => L::CLASS,
            K::Property => L::PROPERTY,
            K::Value => L::VARIABLE,
            K::Macro => L::FUNCTION,
            K::Function => L::FUNCTION,
            K::Constant => L::CONSTANT,
            K::Directive => L::KEYWORD,
            K::File => L::FILE,
            K::Folder => L::FOLDER,
        }),
        detail: c.detail.clone(),
        sort_text: Some(format!("{}{order:05}", c.rank)),
        filter_text: Some(c.label.clone()),
        text_edit: Some(lsp::CompletionTextEdit::Edit(lsp::TextEdit::new(
            replace,
            c.label.clone(),
        ))),
        ..Default::default()
    }
}

#[allow(deprecated)] // `DocumentSymbol::deprecated` must be given, as `None`.
pub fn symbol(text: &str, index: &ide::LineIndex, s: &ide::Symbol) -> lsp::DocumentSymbol {
    use ide::SymbolKind as K;
    lsp::DocumentSymbol {
        name: s.name.clone(),
        detail: s.detail.clone(),
        kind: match s.kind {
            K::Value => lsp::SymbolKind::VARIABLE,
            K::Macro => lsp::SymbolKind::FUNCTION,
            K::Object => lsp::SymbolKind::OBJECT,
            K::Light => lsp::SymbolKind::EVENT,
            K::Camera => lsp::SymbolKind::CONSTRUCTOR,
            K::Settings => lsp::SymbolKind::NAMESPACE,
            K::Material => lsp::SymbolKind::STRUCT,
        },
        tags: None,
        deprecated: None,
        range: range(text, index, s.range.clone()),
        selection_range: range(text, index, s.selection.clone()),
        children: Some(s.children.iter().map(|c| symbol(text, index, c)).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris_and_paths_round_trip() {
        let p = Path::new("/tmp/a dir/é.scn");
        let u = uri(p).unwrap();
        assert_eq!(u.as_str(), "file:///tmp/a%20dir/%C3%A9.scn");
        assert_eq!(path(&u), p);
        let w: lsp::Uri = "file:///C:/scenes/x.scn".parse().unwrap();
        assert_eq!(path(&w), Path::new("C:/scenes/x.scn"));
        let u: lsp::Uri = "untitled:Untitled-1".parse().unwrap();
        assert!(!path(&u).exists());
    }
}
