//! Diagnostics for an editor: the load and the prepare stage of `sppm-lang check`, run on the
//! editor's text under the usual budgets with a shorter step limit, placed in the document.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::outline::Outline;
use super::text::{LineIndex, Position};
use crate::cancel::Cancel;
use crate::diag::{Diagnostic, Severity, SourceMap};
use crate::eval::EvalOptions;
use crate::world::SharedWorld;

/// The budgets of an editor's evaluation: the defaults (`check`'s) with a tenth of the steps,
/// so that a file that would run for long (an endless `#while` being typed) ends in a fraction
/// of a second with the step limit's own diagnostic.
#[derive(Debug, Clone)]
pub struct CheckLimits {
    pub max_steps: u64,
}

impl Default for CheckLimits {
    fn default() -> Self {
        Self {
            max_steps: EvalOptions::default().max_steps / 10,
        }
    }
}

/// A diagnostic placed in the checked document, with its help, labels and trace in the message.
#[derive(Debug, Clone, PartialEq)]
pub struct FileDiagnostic {
    pub start: Position,
    pub end: Position,
    pub severity: Severity,
    pub message: String,
}

/// The outcome of a check.
#[derive(Debug, Clone, Default)]
pub struct Checked {
    pub diagnostics: Vec<FileDiagnostic>,
    /// The global names and values the evaluation left (for hover and completion).
    pub globals: Vec<(String, String)>,
    /// Every file the load read: a change to one of them calls for a new check.
    pub dependencies: Vec<PathBuf>,
    /// Stopped by `cancel`: the result says nothing about the text.
    pub interrupted: bool,
}

/// Checks the document `path` (its text, and the files it includes, read from `world`): the
/// diagnostics of its load and of the prepare stage a render would run. A diagnostic in an
/// included file is placed at the `#include` that leads to it, with its own place in the
/// message. `cancel` stops the work at the next check of either stage.
pub fn check(path: &Path, world: SharedWorld, cancel: Cancel, limits: &CheckLimits) -> Checked {
    let options = EvalOptions {
        max_steps: limits.max_steps,
        // As `check` holds it: the render's limit on this machine.
        memory_limit: Some(crate::prepare::default_memory_limit()),
        cancel: cancel.clone(),
        world,
        ..EvalOptions::default()
    };
    let mut loaded = match crate::eval::load_file(path, &options) {
        Ok(l) => l,
        Err(e) => {
            return Checked {
                diagnostics: vec![FileDiagnostic {
                    start: Position::default(),
                    end: Position::default(),
                    severity: Severity::Error,
                    message: e.with_path(path).to_string(),
                }],
                ..Checked::default()
            };
        }
    };
    let mut found = std::mem::take(&mut loaded.diagnostics);
    if let Some(scene) = loaded
        .scene
        .take()
        .filter(|_| !found.iter().any(Diagnostic::is_error))
    {
        let options = crate::prepare::RenderOptions {
            cancel: cancel.clone(),
            ..Default::default()
        };
        match crate::render::prepare(&scene, &options) {
            Ok((_, prepared)) => found.extend(prepared.warnings()),
            Err(e) if e.interrupted => {}
            Err(e) => found.push(e),
        }
    }
    let interrupted = loaded.interrupted || cancel.is_cancelled();
    let place = Placer::new(path, &loaded.sources);
    Checked {
        diagnostics: if interrupted {
            Vec::new()
        } else {
            found.iter().map(|d| place.diagnostic(d)).collect()
        },
        globals: loaded.globals,
        dependencies: loaded.dependencies,
        interrupted,
    }
}

/// Places the diagnostics of a load in its main document.
struct Placer<'a> {
    sources: &'a SourceMap,
    path: &'a Path,
    /// The main document's text, line index and outline (for the includes).
    main: Option<(&'a str, LineIndex, Outline)>,
    /// The line index of each other file, by its id, made when first needed.
    others: std::cell::RefCell<HashMap<u32, LineIndex>>,
}

impl<'a> Placer<'a> {
    fn new(path: &'a Path, sources: &'a SourceMap) -> Self {
        let main = sources
            .files()
            .iter()
            .find(|f| f.path == path)
            .map(|f| (&*f.text, LineIndex::new(&f.text), Outline::new(&f.text)));
        Self {
            sources,
            path,
            main,
            others: Default::default(),
        }
    }

    /// Whether the span is in the main document, and its range there.
    fn range(&self, span: crate::span::Span) -> Option<(bool, Range<Position>)> {
        let file = self.sources.get(span.file)?;
        let (start, end) = (span.start as usize, span.end as usize);
        if file.path == self.path
            && let Some((text, index, _)) = &self.main
        {
            return Some((true, index.position(text, start)..index.position(text, end)));
        }
        let mut others = self.others.borrow_mut();
        let index = others
            .entry(span.file.0)
            .or_insert_with(|| LineIndex::new(&file.text));
        Some((
            false,
            index.position(&file.text, start)..index.position(&file.text, end),
        ))
    }

    /// `file:line:column` of a span (1-based, as the command line prints it).
    fn place(&self, span: crate::span::Span) -> String {
        match (self.sources.get(span.file), self.range(span)) {
            (Some(_), Some((true, r))) => {
                format!("line {}:{}", r.start.line + 1, r.start.character + 1)
            }
            (Some(f), Some((false, r))) => {
                format!("{}:{}:{}", f.name, r.start.line + 1, r.start.character + 1)
            }
            _ => "(no place)".into(),
        }
    }

    /// Where in the main document a diagnostic in the included file `path` shows: the
    /// `#include` that names it, else the start.
    fn include_of(&self, span: crate::span::Span) -> Range<Position> {
        let (Some(file), Some((text, index, outline))) = (self.sources.get(span.file), &self.main)
        else {
            return Position::default()..Position::default();
        };
        let target = crate::world::normalize(&file.path);
        for i in &outline.includes {
            let (p, _) = super::files::resolve(self.path, &i.path);
            if p == target || file.name == i.path {
                return index.position(text, i.whole.start)..index.position(text, i.whole.end);
            }
        }
        // Included through another file: the first include stands for the chain.
        match outline.includes.first() {
            Some(i) => index.position(text, i.whole.start)..index.position(text, i.whole.end),
            None => Position::default()..Position::default(),
        }
    }

    fn diagnostic(&self, d: &Diagnostic) -> FileDiagnostic {
        let mut message = d.message.clone();
        let range = match self.range(d.span) {
            Some((true, r)) => {
                if !d.label.is_empty() && d.label != d.message {
                    message.push_str(&format!(" ({})", d.label));
                }
                r
            }
            Some((false, _)) => {
                message = format!("{}: {message}", self.place(d.span));
                if !d.label.is_empty() {
                    message.push_str(&format!(" ({})", d.label));
                }
                self.include_of(d.span)
            }
            None => Position::default()..Position::default(),
        };
        if let Some(h) = &d.help {
            message.push_str(&format!("\nhelp: {h}"));
        }
        for (span, label) in &d.labels {
            message.push_str(&format!("\n{}: {label}", self.place(*span)));
        }
        for (span, what) in &d.trace {
            message.push_str(&format!("\n{}: {what}", self.place(*span)));
        }
        FileDiagnostic {
            start: range.start,
            end: range.end,
            severity: d.severity,
            message,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::MemoryWorld;

    fn run(files: &[(&str, &str)]) -> Checked {
        let mut w = MemoryWorld::new();
        for (p, t) in files {
            w.insert(p, *t);
        }
        check(
            Path::new(files[0].0),
            SharedWorld::new(w),
            Cancel::new(),
            &CheckLimits::default(),
        )
    }

    #[test]
    fn errors_are_placed_in_utf16_columns() {
        // `é` is 2 bytes and 1 UTF-16 unit, `😀` 4 bytes and 2 units: `Nope` starts at byte
        // 41 of its line and column 38.
        let c = run(&[(
            "s.scn",
            "#declare A = 1;\n\n#declare S = \"é😀\"; sphere { <0,0,0>, Nope }\n",
        )]);
        let d = c
            .diagnostics
            .iter()
            .find(|d| d.severity == Severity::Error)
            .expect("an error");
        assert_eq!(
            d.start,
            Position {
                line: 2,
                character: 38
            }
        );
        assert_eq!(
            d.end,
            Position {
                line: 2,
                character: 42
            }
        );
        assert!(d.message.contains("Nope"), "{}", d.message);
        assert!(c.globals.iter().any(|(n, v)| n == "A" && v == "1"));
    }

    #[test]
    fn an_error_in_an_include_shows_at_the_include() {
        let c = run(&[
            ("d/s.scn", "#declare X = 1;\n#include \"lib.inc\"\n"),
            ("d/lib.inc", "#declare Y = Missing;\n"),
        ]);
        let d = c
            .diagnostics
            .iter()
            .find(|d| d.severity == Severity::Error)
            .unwrap();
        assert_eq!(d.start.line, 1);
        assert!(d.message.contains("lib.inc:1:14: "), "{}", d.message);
        assert!(d.message.contains("Missing"), "{}", d.message);
        assert!(c.dependencies.contains(&PathBuf::from("d/lib.inc")));
    }

    #[test]
    fn the_prepare_stage_runs_too() {
        // Evaluates fine; preparing finds the camera's `up` along its view.
        let c = run(&[(
            "s.scn",
            "camera { location <0,0,-5> look_at <0,0,0> up <0,0,1> }\nsphere { <0,0,0>, 1 }\nlight { <0,5,0> intensity rgb <1,1,1> }\n",
        )]);
        assert!(
            c.diagnostics
                .iter()
                .any(|d| d.severity == Severity::Error && d.message.contains("parallel")),
            "{:?}",
            c.diagnostics
        );
    }

    #[test]
    fn an_endless_loop_ends_at_the_shorter_step_limit() {
        let t = std::time::Instant::now();
        let c = run(&[(
            "s.scn",
            "#declare I = 0;\n#while (true)\n  #declare I = I + 1;\n#end\n",
        )]);
        assert!(c.diagnostics.iter().any(|d| d.severity == Severity::Error));
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    }
}
