//! Turning [`Diagnostic`]s into miette reports and plain text.

use std::fmt;

use miette::{
    Diagnostic as MietteDiagnostic, GraphicalReportHandler, GraphicalTheme, LabeledSpan,
    NamedSource, SourceCode, SourceSpan,
};

use super::SourceMap;
use super::{Diagnostic, Severity};
use crate::span::Span;

/// One diagnostic in miette's shape: a snippet of the whole file, labels, help, and related
/// reports (trace entries in other files, further errors).
#[derive(Debug)]
struct Rendered {
    message: String,
    severity: miette::Severity,
    source: Option<NamedSource<String>>,
    labels: Vec<LabeledSpan>,
    help: Option<String>,
    related: Vec<Rendered>,
}

impl fmt::Display for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Rendered {}

impl MietteDiagnostic for Rendered {
    fn severity(&self) -> Option<miette::Severity> {
        Some(self.severity)
    }

    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.help
            .as_ref()
            .map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.source.as_ref().map(|s| s as &dyn SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        if self.labels.is_empty() {
            None
        } else {
            Some(Box::new(self.labels.iter().cloned()))
        }
    }

    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn MietteDiagnostic> + 'a>> {
        if self.related.is_empty() {
            None
        } else {
            Some(Box::new(
                self.related.iter().map(|r| r as &dyn MietteDiagnostic),
            ))
        }
    }
}

fn source_span(span: Span) -> SourceSpan {
    SourceSpan::new((span.start as usize).into(), span.len())
}

fn named_source(map: &SourceMap, span: Span) -> Option<NamedSource<String>> {
    let file = map.get(span.file)?;
    Some(NamedSource::new(file.name.clone(), file.text.to_string()).with_language("scn"))
}

fn convert(map: &SourceMap, d: &Diagnostic) -> Rendered {
    let source = named_source(map, d.span);
    let mut labels = Vec::new();
    let mut related = Vec::new();
    if source.is_some() {
        let text = (!d.label.is_empty()).then(|| d.label.clone());
        labels.push(LabeledSpan::new_primary_with_span(
            text,
            source_span(d.span),
        ));
    }
    for (span, label) in &d.labels {
        if span.file == d.span.file && source.is_some() {
            labels.push(LabeledSpan::new_with_span(
                Some(label.clone()),
                source_span(*span),
            ));
        } else {
            related.push(note(map, *span, label));
        }
    }
    for (span, label) in &d.trace {
        related.push(note(map, *span, label));
    }
    Rendered {
        message: d.message.clone(),
        severity: match d.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        },
        source,
        labels,
        help: d.help.clone(),
        related,
    }
}

fn note(map: &SourceMap, span: Span, label: &str) -> Rendered {
    let source = named_source(map, span);
    let labels = if source.is_some() {
        vec![LabeledSpan::new_primary_with_span(
            Some("here".into()),
            source_span(span),
        )]
    } else {
        Vec::new()
    };
    Rendered {
        message: label.to_string(),
        severity: miette::Severity::Advice,
        source,
        labels,
        help: None,
        related: Vec::new(),
    }
}

/// A miette report holding all `diags`: one of them directly, several as related reports
/// under a summary line.
pub fn to_report(map: &SourceMap, diags: &[Diagnostic]) -> miette::Report {
    if diags.len() == 1 {
        return miette::Report::new(convert(map, &diags[0]));
    }
    let errors = diags.iter().filter(|d| d.is_error()).count();
    let warnings = diags.len() - errors;
    let message = match (errors, warnings) {
        (0, w) => format!("{w} warnings"),
        (e, 0) => format!("{e} errors"),
        (e, w) => format!("{e} error{}, {w} warning{}", plural(e), plural(w)),
    };
    miette::Report::new(Rendered {
        message,
        severity: if errors > 0 {
            miette::Severity::Error
        } else {
            miette::Severity::Warning
        },
        source: None,
        labels: Vec::new(),
        help: None,
        related: diags.iter().map(|d| convert(map, d)).collect(),
    })
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Renders each diagnostic as miette's graphical output without colors, `width` columns wide,
/// one after the other. Deterministic: for snapshot tests and non-terminal output.
pub fn render_plain(map: &SourceMap, diags: &[Diagnostic], width: usize) -> String {
    let handler = GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor())
        .with_width(width)
        .with_links(false);
    let mut out = String::new();
    for d in diags {
        let r = convert(map, d);
        if handler.render_report(&mut out, &r).is_err() {
            out.push_str(&d.message);
            out.push('\n');
        }
    }
    out
}
