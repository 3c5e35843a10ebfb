//! The interpreter: the evaluator's state and the statements of a body (properties,
//! positional values, directives, macro calls), which assemble a [`Scene`].
//!
//! Errors are collected per top-level statement, so that several independent errors are
//! reported together. Loops and macro recursion are bounded by [`EvalOptions`].
//!
//! The files of this module, leaves first:
//! - `value`: runtime values and the definitions they hold (imports nothing else from `eval`);
//! - `builtins`: built-in functions and constants;
//! - `args`: property arguments and their readers; `props`: property specs and transforms;
//! - `scope`: bindings and lookups; `expr`: expressions; `random`: random streams (`seed`,
//!   `rand`); `directives`: directives; `macros`: macro calls, as statements and as values;
//!   `include`: `#include` and path resolution; `stdlib`: the built-in `std/` files;
//! - `memory`: the memory a load holds (parsed text, strings, images) against its limit;
//! - `blocks`: one builder per block kind (the `blocks::Sink` of its body);
//! - `lower`: lowering definitions into scene objects, material and texture ids, and assets.

mod animation;
mod args;
mod blocks;
mod builtins;
mod directives;
mod expr;
mod function;
mod function_pattern;
mod include;
mod load;
mod lower;
mod macros;
mod memory;
mod props;
mod random;
mod scope;
mod stdlib;
mod strings;
mod value;

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;

pub use animation::{RangeOverride, frame_range, load_frame};
pub use blocks::{PropertyInfo, block_names, block_properties, top_level_properties};
pub use builtins::{CONSTANTS, FUNCTIONS};
pub use function::compile_function;
pub use load::{load_file, load_source};
pub use stdlib::FILES as STD_FILES;
pub use value::Value;

use crate::diag::{Diagnostic, Error, SourceResult, suggest};
use crate::scene::Scene;
use crate::span::Span;
use crate::syntax::SourceMap;
use crate::syntax::ast::*;
use args::Arg;
use blocks::{Sink, TopSink};
use scope::{Binding, Frame};

/// Limits that keep evaluation finite.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalOptions {
    /// Most iterations one `#while` or `#for` loop may run.
    pub max_iterations: u64,
    /// Deepest macro call nesting (recursion depth). Lowered, with a word when a scene
    /// reaches it, when the evaluation's stack had to be smaller (see [`MAX_EVAL_NESTING`]).
    pub max_depth: usize,
    /// Most objects a scene may produce (guards exponential recursion).
    pub max_objects: usize,
    /// Most evaluation steps (statements, properties, directives, loop iterations, macro
    /// calls, the operations of expressions and the tests of `#if` and `#switch` clauses,
    /// counted together) one load may take: a budget for the whole evaluation, so that
    /// nested loops or exponential recursion that each stay under their own limits still end.
    pub max_steps: u64,
    /// The render's memory limit (bytes), as given to `prepare`. The load holds to it too: the
    /// text it parses (every include), the strings it builds and the images it decodes count
    /// in one running total, and the file, string or image that would pass the limit is
    /// refused (an image from its header, before it is decoded). `None`:
    /// [`DEFAULT_PARSE_MEMORY`].
    pub memory_limit: Option<u64>,
    /// Raised by the caller to stop the load: the evaluation checks it at every step (and
    /// before and after parsing, which cannot stop midway) and ends with
    /// [`Loaded::interrupted`].
    pub cancel: crate::cancel::Cancel,
    /// The animation frame being evaluated: what `clock`, `frame_number` and the other
    /// animation names read ([`crate::scene::animation_value`]). `None`: a still, where they
    /// read 0.
    pub frame: Option<crate::scene::Frame>,
    /// Where the scene file, its includes and its assets are read from: the disk unless set
    /// (a [`crate::world::MemoryWorld`] supplies them from memory).
    pub world: crate::world::SharedWorld,
}

/// Deepest nesting of blocks and macro calls together. Each level takes about 3.3 KB of the
/// evaluation thread's stack (measured: a macro nesting 60 `union` blocks per call, release
/// build; a macro call with its `#if` body, about 2.9 KB of resident stack, dev build); the
/// thread gets `EVAL_STACK`, three times what this many levels of blocks need. A smaller
/// stack, taken when the address space is limited, holds proportionally fewer levels.
pub const MAX_EVAL_NESTING: usize = 100_000;
/// The memory limit a load (its parsed text, strings and images) is held to when the caller
/// gives none ([`EvalOptions::memory_limit`]): a render's default on a machine with 4 GiB or
/// more.
pub const DEFAULT_PARSE_MEMORY: u64 = 2 << 30;
/// Most `#debug` and `#warning` messages one load keeps (a loop printing each iteration stays
/// readable and bounded); past it, one last note says the rest were left out.
pub const MAX_MESSAGES: usize = 1000;
/// Most warnings one load keeps (a warning repeated by a loop or on every line of a generated
/// file stays readable, and its memory bounded); past it, one note says the rest were left out.
pub const MAX_WARNINGS: usize = 1000;
/// Most errors one load counts before its evaluation stops, with a note that says so: a mistake
/// repeated in a loop, in a macro called often or on every line of a generated file stays
/// readable and quick to report. An error repeated at the same place (a macro's body, called
/// again) counts each time but is shown once.
pub const MAX_ERRORS: usize = 100;
/// Most "did you mean" searches over the scene's own names one load makes (each reads every
/// declared name); later errors of the kind get the plain help.
pub const MAX_NAME_SUGGESTIONS: usize = 20;
/// Longest string a scene may build (bytes).
pub const MAX_STRING_BYTES: usize = 1 << 24;
/// Bytes of string built, compared or scanned that count as one evaluation step.
pub const STRING_BYTES_PER_STEP: usize = 16;
/// Evaluation steps per array element built, and per macro argument bound.
pub const STEPS_PER_ELEMENT: u64 = 4;

/// The steps that work on `v` costs beyond the expression's own: its string bytes (a string
/// joined, compared or measured is copied or scanned whole) and its array elements (made one
/// by one). So the budget bounds what a loop builds, not only how often it runs: a string of
/// 8 MiB joined a million times, or an array of 4 000 numbers made a million times, runs out
/// of steps instead of running for an hour, and what a scene can build in all (about 800 MB of
/// strings or 12 million array elements at the default budget) bounds its memory too.
pub(crate) fn work_of(v: &Value) -> u64 {
    match v {
        Value::Str(s) => (s.len() / STRING_BYTES_PER_STEP) as u64,
        Value::Array(xs) => xs.len() as u64 * STEPS_PER_ELEMENT,
        _ => 0,
    }
}

/// Stack of the evaluation thread. Reserved, not touched: only what the nesting uses is paid.
const EVAL_STACK: usize = 1 << 30;

/// Stacks tried for the evaluation thread, largest first. Under an address-space limit
/// (`ulimit -v`) the largest may not be reservable (a render's thread pool reserves its own
/// stacks first); a smaller one holds fewer levels (see [`nesting_limit`]).
const EVAL_STACKS: [usize; 3] = [EVAL_STACK, 1 << 28, 1 << 26];

/// Stack bytes allowed per level of nesting: [`EVAL_STACK`] shared by [`MAX_EVAL_NESTING`]
/// levels (about 10.7 KB, three times what a level of blocks takes).
const STACK_PER_LEVEL: usize = EVAL_STACK / MAX_EVAL_NESTING;

/// Deepest nesting of blocks and macro calls a stack of `stack` bytes holds.
fn nesting_limit(stack: usize) -> usize {
    (stack / STACK_PER_LEVEL).min(MAX_EVAL_NESTING)
}

/// "1 GiB", "256 MiB": a stack size in words.
fn stack_words(bytes: usize) -> String {
    if bytes >= 1 << 30 && bytes.is_multiple_of(1 << 30) {
        format!("{} GiB", bytes >> 30)
    } else {
        format!("{} MiB", bytes >> 20)
    }
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            max_iterations: 1_000_000,
            max_depth: 256,
            max_objects: 1_000_000,
            max_steps: 50_000_000,
            memory_limit: None,
            cancel: crate::cancel::Cancel::default(),
            frame: None,
            world: crate::world::SharedWorld::default(),
        }
    }
}

/// The outcome of a load: the scene (if there were no errors), every diagnostic (errors and
/// warnings), and the sources needed to render the diagnostics.
#[derive(Debug, Clone, Default)]
pub struct Loaded {
    pub scene: Option<Scene>,
    pub diagnostics: Vec<Diagnostic>,
    pub sources: SourceMap,
    /// Every file the load read or tried to read (the scene, includes, images, meshes), also
    /// when it failed: what `watch` watches.
    pub dependencies: Vec<PathBuf>,
    /// The evaluation could not start in this environment (no thread with a stack could be
    /// made, as under a low address-space limit): not the scene's fault. The diagnostics say
    /// what failed.
    pub environment: bool,
    /// The caller cancelled the load ([`EvalOptions::cancel`]): no scene, and an error
    /// "interrupted" after the errors found before it; not the scene's fault.
    pub interrupted: bool,
    /// The evaluation read an animation name (`clock`, `frame_number`, ...): another frame
    /// may give another scene. When false every frame gives this one.
    pub animated: bool,
    /// The global names as the load left them, sorted, each with its value as a message shows
    /// it (numbers, vectors, colours and strings as written, cut to 200 bytes) or its type
    /// ("an object"): what an editor shows on hover.
    pub globals: Vec<(String, String)>,
}

impl Loaded {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

pub(crate) struct Evaluator {
    options: EvalOptions,
    pub(crate) sources: SourceMap,
    pub(crate) scene: Scene,
    globals: HashMap<String, Binding>,
    frames: Vec<Frame>,
    /// Names whose declaration failed: their uses are not reported again.
    poisoned: HashSet<String>,
    include_stack: Vec<PathBuf>,
    pub(crate) errors: Vec<Diagnostic>,
    pub(crate) warnings: Vec<Diagnostic>,
    warned: HashSet<(Span, String)>,
    /// The errors shown so far, by place and message (an error repeated there is shown once).
    reported: HashSet<(Span, String)>,
    /// Errors raised so far, repeated ones included (see [`MAX_ERRORS`]).
    error_count: usize,
    /// "Did you mean" searches over the declared names so far (see [`MAX_NAME_SUGGESTIONS`]).
    name_suggestions: usize,
    pub(crate) assets: lower::Assets,
    /// Every file read or tried: the scene, includes, images, meshes (see [`Loaded`]).
    dependencies: Vec<PathBuf>,
    /// Steps taken so far (see [`EvalOptions::max_steps`]).
    steps: u64,
    /// Set once the step budget ran out or an `#error` stopped the load: every later step fails
    /// silently, so the evaluation unwinds at once with the one error already reported.
    exhausted: bool,
    /// Set once the caller's cancel was seen ([`Evaluator::interrupted`]).
    interrupted: bool,
    /// Set once an animation name was read ([`Loaded::animated`]).
    pub(crate) animated: bool,
    /// `#switch`es and loops around the current item that a `#break` may leave (within one
    /// block body or macro body: blocks and macro calls start again at 0).
    pub(crate) break_targets: usize,
    /// Set by `#break` until the `#switch` or loop it leaves has seen it.
    breaking: bool,
    /// `#debug` and `#warning` messages so far (see [`MAX_MESSAGES`]).
    messages: usize,
    /// The scene's own file: only its declarations can be reported unused (an included file,
    /// a library, declares more than one scene uses).
    main_file: Option<crate::span::FileId>,
    /// Warnings kept so far (see [`Evaluator::warn`]).
    warning_count: usize,
    /// Set while the value of a `#declare`/`#local` that is a camera block is evaluated: that
    /// block starts from the default camera (taken by the block).
    pub(crate) camera_from_defaults: bool,
    /// The name a `#declare`/`#local` of a function binds, while the function is compiled: its
    /// body may not call it.
    pub(crate) defining: Option<String>,
    /// Blocks being evaluated, innermost last (with `frames`, bounded by [`MAX_EVAL_NESTING`]).
    pub(crate) block_depth: usize,
    /// The items being run are a blob's body (its `sphere`s and `cylinder`s are components).
    pub(crate) in_blob: bool,
    /// The evaluation thread's stack (bytes): it bounds the nesting ([`nesting_limit`]).
    stack: usize,
    /// Object parts copied into containers so far (see [`Evaluator::count_parts`]).
    parts_copied: usize,
    /// Bytes of scene text read so far (the scene and every include).
    pub(crate) source_bytes: u64,
    /// The memory the load holds so far (see [`memory`]).
    held: memory::Held,
    /// How often each name-like word occurs in the sources read (see
    /// [`Evaluator::warn_unused`]), and how many files it counted; made when first needed.
    mentions: Option<(usize, HashMap<String, u32>)>,
}

/// "`word` is not a property of a material", with the POV-Ray spelling's counterpart or the
/// nearest property names.
fn not_a_property(sink: &dyn Sink, word: &str, span: Span) -> Diagnostic {
    let kind = sink.kind();
    let names: Vec<&str> = sink.props().iter().map(|p| p.name).collect();
    let e = Error::new(format!("`{word}` is not a property of {kind}")).label("unknown property");
    let near = crate::diag::suggest_all(word, names.iter().copied(), 3);
    let e = if let Some(hint) = crate::syntax::povray_hint(word, &kind) {
        e.help(hint)
    } else if !near.is_empty() {
        let near: Vec<String> = near.iter().map(|n| format!("`{n}`")).collect();
        e.help(format!("did you mean {}?", or_list(&near)))
    } else if names.is_empty() {
        e.help(format!("{kind} takes no properties"))
    } else {
        e.help(format!("{kind} accepts: {}", names.join(", ")))
    };
    e.at(span)
}

/// The name an expression starts with, if it is a name or a chain of binary operations whose
/// first operand is one.
fn leftmost_name(mut e: &Expr) -> Option<&str> {
    loop {
        match &e.kind {
            ExprKind::Ident(name) => return Some(name),
            ExprKind::Binary(_, a, _) => e = a,
            _ => return None,
        }
    }
}

/// `a`, `a or b`, `a, b or c`.
fn or_list(xs: &[String]) -> String {
    match xs {
        [] => String::new(),
        [a] => a.clone(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// A silent error: its cause was already reported.
fn silent() -> Vec<Diagnostic> {
    Vec::new()
}

impl Evaluator {
    fn new(options: EvalOptions) -> Self {
        Self {
            options,
            sources: SourceMap::new(),
            scene: lower::empty_scene(),
            globals: HashMap::new(),
            frames: Vec::new(),
            poisoned: HashSet::new(),
            include_stack: Vec::new(),
            errors: Vec::new(),
            warnings: Vec::new(),
            warned: HashSet::new(),
            reported: HashSet::new(),
            error_count: 0,
            name_suggestions: 0,
            assets: lower::Assets::default(),
            dependencies: Vec::new(),
            steps: 0,
            exhausted: false,
            interrupted: false,
            animated: false,
            break_targets: 0,
            breaking: false,
            messages: 0,
            main_file: None,
            block_depth: 0,
            in_blob: false,
            warning_count: 0,
            camera_from_defaults: false,
            defining: None,
            stack: EVAL_STACK,
            parts_copied: 0,
            source_bytes: 0,
            held: memory::Held::default(),
            mentions: None,
        }
    }

    /// Keeps a warning, once per place and message, up to [`MAX_WARNINGS`]; past them, one
    /// note says the rest were left out.
    pub(crate) fn warn(&mut self, d: Diagnostic) {
        if self.warning_count >= MAX_WARNINGS {
            if self.warning_count == MAX_WARNINGS {
                self.warning_count += 1;
                self.warnings.push(
                    Diagnostic::note(
                        d.span,
                        format!("more than {MAX_WARNINGS} warnings: the rest are not shown"),
                    )
                    .with_label("this one and the later ones"),
                );
            }
            return;
        }
        if self.warned.insert((d.span, d.message.clone())) {
            self.warning_count += 1;
            self.warnings.push(d);
        }
    }

    /// Runs top-level items, collecting the errors of each item and going on, until
    /// [`MAX_ERRORS`] errors were raised.
    /// Runs the file's items. Each item's tree is dropped once it has run (what a declaration
    /// or macro keeps is shared), so that a large scene's objects reuse its memory.
    fn run_top(&mut self, items: &mut [Item], sink: &mut dyn Sink) {
        let mut i = 0;
        while i < items.len() {
            let start = i;
            let result = self.step(items, &mut i, sink);
            for item in &mut items[start..i] {
                *item = Item::Comma(item.span());
            }
            if let Err(ds) = result {
                self.report(ds);
                if self.error_count >= MAX_ERRORS
                    && let Some(next) = items.get(i)
                {
                    self.errors.push(
                        Diagnostic::note(
                            next.span(),
                            format!("more than {MAX_ERRORS} errors: the evaluation stopped"),
                        )
                        .with_label("not evaluated from here on")
                        .with_help(
                            "fix the errors above first (an error repeated at the same place, \
                             in a macro or a loop, is shown once)",
                        ),
                    );
                    return;
                }
            }
        }
    }

    /// Records errors, each place and message shown once.
    fn report(&mut self, ds: Vec<Diagnostic>) {
        for d in ds {
            self.error_count += 1;
            if self.reported.insert((d.span, d.message.clone())) {
                self.errors.push(d);
            }
        }
    }

    /// Whether one more "did you mean" search over the declared names is allowed (see
    /// [`MAX_NAME_SUGGESTIONS`]); counts it.
    pub(crate) fn may_suggest_name(&mut self) -> bool {
        self.name_suggestions += 1;
        self.name_suggestions <= MAX_NAME_SUGGESTIONS
    }

    /// Runs a block body or directive body.
    pub(crate) fn run_items(&mut self, items: &[Item], sink: &mut dyn Sink) -> SourceResult<()> {
        let mut i = 0;
        while i < items.len() && !self.breaking {
            self.step(items, &mut i, sink)?;
        }
        Ok(())
    }

    /// Counts one step against the budget; the error when it has run out.
    pub(crate) fn tick(&mut self, span: Span) -> SourceResult<()> {
        self.charge(1, span)
    }

    /// Counts `steps` steps against the budget: work whose cost grows with the size of its
    /// values (see [`work_of`]).
    pub(crate) fn charge(&mut self, steps: u64, span: Span) -> SourceResult<()> {
        if self.exhausted || self.interrupted() {
            return Err(silent());
        }
        self.steps = self.steps.saturating_add(steps);
        if self.steps > self.options.max_steps {
            self.exhausted = true;
            return Err(vec![
                Error::new(format!(
                    "the evaluation took more than {} steps",
                    self.options.max_steps
                ))
                .label("the budget ran out here")
                .help(
                    "look for loops or recursion that do far more work than intended; raise \
                     the budget with `--max-steps` if the scene really needs it",
                )
                .at(span),
            ]);
        }
        Ok(())
    }

    /// Whether the caller cancelled the load ([`EvalOptions::cancel`]); once it has, every
    /// later step fails silently, as when the budget ran out, and the load ends with
    /// [`Loaded::interrupted`].
    fn interrupted(&mut self) -> bool {
        if !self.interrupted && self.options.cancel.is_cancelled() {
            self.interrupted = true;
        }
        self.interrupted
    }

    /// Fails when one more level of blocks or macro calls would pass [`MAX_EVAL_NESTING`], or
    /// the lower limit of a smaller stack ([`Evaluator::stack_limit`]).
    pub(crate) fn check_nesting(&self, span: Span) -> SourceResult<()> {
        let limit = nesting_limit(self.stack);
        if self.block_depth + self.frames.len() >= limit {
            let message =
                format!("blocks, directive bodies and macro calls nested deeper than {limit}");
            let e = match self.stack_limit() {
                Some((why, help)) => Error::new(format!(
                    "{message} (lowered from {MAX_EVAL_NESTING}: {why})"
                ))
                .help(help),
                None => Error::new(message)
                    .help("make sure the recursion stops (e.g. `#if (Depth > 0)`)"),
            };
            return Err(vec![e.label("one level too deep").at(span)]);
        }
        Ok(())
    }

    /// When the stack is smaller than [`EVAL_STACK`] (the address space was limited): why the
    /// nesting limit is lower than usual, and what raises it.
    pub(crate) fn stack_limit(&self) -> Option<(String, String)> {
        (nesting_limit(self.stack) < MAX_EVAL_NESTING).then(|| {
            (
                format!(
                    "the address space is limited, so the evaluation's stack is {} instead of {}",
                    stack_words(self.stack),
                    stack_words(EVAL_STACK)
                ),
                "raise the address-space limit (`ulimit -v`, `prlimit --as`; and for `render` \
                 use fewer `--threads`) so the full stack can be reserved, or make the \
                 recursion stop sooner"
                    .to_string(),
            )
        })
    }

    /// The deepest macro nesting allowed: `--max-depth`, unless the stack holds fewer levels.
    pub(crate) fn max_macro_depth(&self) -> usize {
        self.options.max_depth.min(nesting_limit(self.stack))
    }

    fn step(&mut self, items: &[Item], i: &mut usize, sink: &mut dyn Sink) -> SourceResult<()> {
        let item = &items[*i];
        *i += 1;
        self.tick(item.span())?;
        match item {
            Item::Comma(_) => Ok(()),
            Item::Directive(d) => self.directive(d, sink),
            Item::Keyword(kw) => {
                let Some(spec) = sink.prop_spec(&kw.text) else {
                    // Skip the keyword's would-be arguments.
                    while let Some(Item::Expr(_) | Item::Comma(_)) = items.get(*i) {
                        *i += 1;
                    }
                    return Err(vec![not_a_property(sink, &kw.text, kw.span)]);
                };
                let mut args: Vec<Arg> = Vec::new();
                let mut j = *i;
                while args.len() < spec.max as usize {
                    let mut k = j;
                    if !args.is_empty() {
                        if let Some(Item::Comma(_)) = items.get(k) {
                            k += 1;
                        } else {
                            break;
                        }
                    }
                    match items.get(k) {
                        Some(Item::Expr(e)) => {
                            let value = if spec.word {
                                match &e.kind {
                                    ExprKind::Ident(w) => Value::Str(Rc::from(w.as_str())),
                                    _ => self.eval(e)?,
                                }
                            } else {
                                self.eval(e)?
                            };
                            args.push(Arg {
                                value,
                                span: e.span,
                            });
                            j = k + 1;
                        }
                        // A word that is also a property keyword (`wrap mirror`).
                        Some(Item::Keyword(w)) if spec.word => {
                            args.push(Arg {
                                value: Value::Str(Rc::from(w.text.as_str())),
                                span: w.span,
                            });
                            j = k + 1;
                        }
                        _ => break,
                    }
                }
                *i = j;
                if args.len() < spec.min as usize {
                    let what = spec.hint;
                    let span = kw.span;
                    return Err(vec![
                        Error::new(format!("`{}` needs {what}", kw.text))
                            .label(format!("missing {what}"))
                            .help(format!("write e.g. `{} {}`", kw.text, spec.example))
                            .at(span),
                    ]);
                }
                sink.property(self, kw, args)
            }
            Item::Expr(e) => {
                // An undeclared name followed by a value reads as a misspelt property
                // (`difuse 0.5`, POV-Ray's `right x*4/3`, `foo 1`): say so, with the nearest
                // properties. A name far from every property only when a literal follows and
                // it is not close to a declared name: `Radus material { ... }` or
                // `union { Wheel Body }` are misspelt or undeclared values.
                // A POV-Ray word of this block that is no name here, standing alone
                // (`shadowless`, `perspective`) or heading an expression (`right -x*4/3` reads
                // as a subtraction): its hint.
                if let Some(name) = leftmost_name(e)
                    && self.lookup_quiet(name).is_none()
                    && !self.poisoned.contains(name)
                    && crate::syntax::povray_hint(name, &sink.kind()).is_some()
                {
                    while let Some(Item::Expr(_) | Item::Comma(_)) = items.get(*i) {
                        *i += 1;
                    }
                    return Err(vec![not_a_property(sink, name, e.span)]);
                }
                if let ExprKind::Ident(name) = &e.kind
                    && let Some(Item::Expr(next)) = items.get(*i)
                    && self.lookup_quiet(name).is_none()
                    && !self.poisoned.contains(name)
                    && !blocks::is_block_name(name)
                    && (crate::syntax::povray_hint(name, &sink.kind()).is_some()
                        || suggest(name, sink.props().iter().map(|p| p.name)).is_some()
                        || (matches!(
                            next.kind,
                            ExprKind::Number(_)
                                | ExprKind::Vector(_)
                                | ExprKind::Unary(..)
                                | ExprKind::Str(_)
                                | ExprKind::Bool(_)
                        ) && !self.near_a_known_name(name)))
                {
                    while let Some(Item::Expr(_) | Item::Comma(_)) = items.get(*i) {
                        *i += 1;
                    }
                    return Err(vec![not_a_property(sink, name, e.span)]);
                }
                if let ExprKind::Call { name, args } = &e.kind
                    && let Some(Value::Macro(m)) = self.lookup_quiet(&name.text)
                {
                    return self.call_macro(&m, name, args, e.span, sink);
                }
                let v = self.eval(e)?;
                sink.positional(self, v, e.span)
            }
        }
    }
}

#[cfg(test)]
mod tests;
