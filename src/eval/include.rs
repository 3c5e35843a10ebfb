//! `#include` (of scene files and of the built-in standard library) and the resolution of file
//! paths relative to the file that names them.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::Evaluator;
use super::blocks::Sink;
use super::scope::Frame;
use super::stdlib;
use crate::diag::{Error, SourceResult, size_text, suggest};
use crate::span::{FileId, Span};
use crate::syntax::parse;

impl Evaluator {
    pub(super) fn include(
        &mut self,
        path: &str,
        span: Span,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        if path.starts_with("std/") {
            return self.include_std(path, span, sink);
        }
        let resolved = self.resolve_path(path, span);
        let canon = self.options.world.canonical(&resolved);
        if let Some(pos) = self.include_stack.iter().position(|p| *p == canon) {
            let chain: Vec<String> = self.include_stack[pos..]
                .iter()
                .chain(std::iter::once(&canon))
                .map(|p| {
                    p.file_name().map_or_else(
                        || p.display().to_string(),
                        |n| n.to_string_lossy().into_owned(),
                    )
                })
                .collect();
            return Err(vec![
                Error::new(format!("cyclic include of `{path}`"))
                    .label("this file is already being included")
                    .help(format!("the include chain is {}", chain.join(" → ")))
                    .at(span),
            ]);
        }
        if self.include_stack.len() > 64 {
            return Err(vec![
                Error::new("includes nested more than 64 deep")
                    .label("the 65th nested include")
                    .help("include the files one after another from the scene, not each from the last")
                    .at(span),
            ]);
        }
        // Recorded before the read so that `watch` also waits for a file that is missing.
        self.dependencies.push(resolved.clone());
        // All the text one load reads (the scene and every include, also the same file included
        // again in a loop) is bounded by one file's limit.
        let budget = crate::files::MAX_SOURCE_BYTES.saturating_sub(self.source_bytes);
        // A file that would fit alone but not in what is left says so (its own size is not
        // the problem).
        let beyond_total = budget < crate::files::MAX_SOURCE_BYTES
            && self
                .options
                .world
                .size(&resolved)
                .is_some_and(|n| n > budget);
        if budget == 0 || beyond_total {
            return Err(vec![
                Error::new(format!(
                    "the scene and its includes read more than {} bytes in all",
                    crate::files::MAX_SOURCE_BYTES
                ))
                .label("one include too many")
                .help("is a file included inside a loop? declare what it defines once instead")
                .at(span),
            ]);
        }
        let text =
            crate::world::read_text(&*self.options.world, &resolved, budget).map_err(|e| {
                let label = match &e {
                    crate::files::FileError::Io(io)
                        if io.kind() == std::io::ErrorKind::NotFound =>
                    {
                        "not found"
                    }
                    crate::files::FileError::Io(_) => "cannot be read",
                    crate::files::FileError::Refused(_) => "not a readable scene file",
                };
                // POV-Ray's files only where the file is missing (one that exists but cannot be
                // read, a FIFO say, is the scene's own).
                let povray = match &e {
                    crate::files::FileError::Io(io)
                        if io.kind() == std::io::ErrorKind::NotFound =>
                    {
                        stdlib::povray_include(path)
                    }
                    _ => None,
                };
                let help = match povray {
                    Some(h) => format!("POV-Ray's `{path}`: {h}"),
                    None => format!(
                        "the path is resolved relative to the including file: {}",
                        resolved.display()
                    ),
                };
                vec![
                    Error::new(format!("cannot read included file `{path}`: {e}"))
                        .label(label)
                        .help(help)
                        .at(span),
                ]
            })?;
        self.source_bytes += text.len() as u64;
        let file = self
            .sources
            .add(&resolved, resolved.display().to_string(), text.clone());
        self.run_included(file, &text, canon, span, sink)
    }

    /// `#include "std/NAME.scn"`: a file of the standard library, never looked for on disk.
    fn include_std(&mut self, path: &str, span: Span, sink: &mut dyn Sink) -> SourceResult<()> {
        let Some(text) = stdlib::get(path) else {
            let names: Vec<&str> = stdlib::FILES.iter().map(|(p, _)| *p).collect();
            let mut e = Error::new(format!("there is no standard file `{path}`"))
                .label("not in the standard library");
            e = match suggest(path, names.iter().copied()) {
                Some(s) => e.help(format!("did you mean `{s}`?")),
                None => e.help(format!("the standard files are {}", names.join(", "))),
            };
            return Err(vec![e.at(span)]);
        };
        let key = PathBuf::from(format!("<built-in>/{path}"));
        if self.include_stack.contains(&key) {
            return Err(vec![
                Error::new(format!("cyclic include of `{path}`"))
                    .label("this file is already being included")
                    .at(span),
            ]);
        }
        let file = self.sources.add(&key, path.to_string(), text.to_string());
        self.run_included(file, text, key, span, sink)
    }

    /// Parses a file's text, unless parsing it would need more memory than the load has left
    /// ([`crate::syntax::parse_memory`], against what the load holds already and
    /// [`super::EvalOptions::memory_limit`] or [`super::DEFAULT_PARSE_MEMORY`]): the error
    /// stands at `include` (the `#include` that reads the file) or, for the scene file itself,
    /// at its first character. What it takes is counted as held ([`super::memory`]).
    pub(super) fn parse_within_memory(
        &mut self,
        file: FileId,
        text: &str,
        include: Option<Span>,
    ) -> SourceResult<Vec<crate::syntax::ast::Item>> {
        let limit = self.memory_limit();
        let left = self.memory_left();
        let need = crate::syntax::parse_memory(text);
        if need > left {
            let (what, label, span) = match include {
                Some(span) => ("this included file", "included here", span),
                None => (
                    "the scene file",
                    "the file starts here",
                    Span::new(file, 0, 0),
                ),
            };
            // Sizes that round to the same text are given in bytes.
            let (need_text, left_text) = match (size_text(need), size_text(left)) {
                (a, b) if a == b => (format!("{need} bytes"), format!("{left} bytes")),
                pair => pair,
            };
            let room = if self.held.total() == 0 {
                format!("the {left_text} allowed")
            } else {
                format!(
                    "the {left_text} left of the {} allowed: the load holds {} already ({})",
                    size_text(limit),
                    size_text(self.held.total()),
                    self.held.parts()
                )
            };
            return Err(vec![
                Error::new(format!(
                    "{what} is too large to parse within the memory limit: its {} of text would \
                     need up to {need_text} to parse, more than {room}",
                    size_text(text.len() as u64),
                ))
                .label(label)
                .help(
                    "raise `--memory-limit`, or make the many objects with a `#for` loop or a \
                     mesh file (`mesh { \"file.obj\" }`) instead of writing each one out",
                )
                .at(span),
            ]);
        }
        self.held.text += need;
        parse(file, text)
    }

    /// Parses and runs an included file's text; errors inside get the include as their trace.
    fn run_included(
        &mut self,
        file: FileId,
        text: &str,
        key: PathBuf,
        span: Span,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        let items = match self.parse_within_memory(file, text, Some(span)) {
            Ok(items) => items,
            Err(e) => {
                // The file is not run, so what it declares is poisoned: its uses stay quiet
                // instead of each being an unknown identifier (its syntax errors are the cause).
                // Read from its text, its `#declare`s and `#macro`s wherever they stand: an
                // unknown name elsewhere is still reported.
                self.poisoned.extend(crate::syntax::declared_names(text));
                return Err(e);
            }
        };
        self.include_stack.push(key);
        // The file's top-level `#local`s live in a frame of its own, gone when it ends (its
        // unused ones are not reported: see `warn_unused`).
        self.frames.push(Frame {
            vars: HashMap::new(),
            file: true,
        });
        let r = self.run_items(&items, sink);
        self.frames.pop();
        self.include_stack.pop();
        r.map_err(|mut ds| {
            for d in &mut ds {
                d.trace.push((span, "in the file included here".into()));
            }
            ds
        })
    }

    /// A path from source text, relative to the directory of the file the span is in.
    pub(crate) fn resolve_path(&self, path: &str, span: Span) -> PathBuf {
        let p = Path::new(path);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        match self.sources.get(span.file).and_then(|f| f.path.parent()) {
            Some(dir) => dir.join(p),
            None => p.to_path_buf(),
        }
    }

    /// The help for a file named at `span` (a string) that cannot be read: to write `/` for a
    /// backslash (a Windows path, whose `\t` became a tab); else where its path is resolved
    /// from, and, when the path as written names a file relative to the current folder instead
    /// (written from where the command runs), that it should be written from the file's folder.
    pub(crate) fn path_help(&self, span: Span) -> String {
        let written = self.sources.snippet(span).trim_matches('"');
        if written.contains('\\') {
            // A Windows path: `"tex\tiles.png"` reads as "tex", a tab, "iles.png".
            let slashes = written.replace("\\\\", "/").replace('\\', "/");
            return format!(
                "write paths with `/`: `\"{slashes}\"` (in a string `\\` starts an escape: \
                 `\\t` is a tab, `\\n` a line break)"
            );
        }
        let dir = self
            .sources
            .get(span.file)
            .and_then(|f| f.path.parent())
            .map(|d| d.display().to_string())
            .filter(|d| !d.is_empty());
        let Some(dir) = dir else {
            return "the path is resolved relative to the folder of the file that names it".into();
        };
        let mut help = format!(
            "the path is resolved relative to the folder of the file that names it, `{dir}`"
        );
        if Path::new(written).is_relative()
            && self.options.world.size(Path::new(written)).is_some()
            && self
                .options
                .world
                .size(&self.resolve_path(written, span))
                .is_none()
        {
            help += &format!(
                ", not the current folder (where `{written}` is): write the path from `{dir}`"
            );
        }
        help
    }
}
