//! The interpreter: statements, scopes, expressions, and the assembly of a [`Scene`].
//!
//! Errors are collected per top-level statement, so that several independent errors are
//! reported together. Loops and macro recursion are bounded by [`EvalOptions`].

mod builtins;
mod objects;
mod value;

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DVec2, DVec3};

pub use builtins::{CONSTANTS, FUNCTIONS};
pub use value::Value;

use crate::diag::{At, Diagnostic, Error, SourceResult, suggest};
use crate::scene::Scene;
use crate::span::Span;
use crate::syntax::ast::*;
use crate::syntax::{SourceMap, parse};
use objects::{Sink, TopSink};

/// Limits that keep evaluation finite.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalOptions {
    /// Most iterations one `#while` or `#for` loop may run.
    pub max_iterations: u64,
    /// Deepest macro call nesting (recursion depth).
    pub max_depth: usize,
    /// Most objects a scene may produce (guards exponential recursion).
    pub max_objects: usize,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            max_iterations: 1_000_000,
            max_depth: 256,
            max_objects: 5_000_000,
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
}

impl Loaded {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Reads, parses and evaluates a scene file. `Err` only when the file itself cannot be read.
pub fn load_file(path: &Path, options: &EvalOptions) -> std::io::Result<Loaded> {
    let text = std::fs::read_to_string(path)?;
    Ok(load_source_at(
        path,
        &path.display().to_string(),
        text,
        options,
    ))
}

/// Parses and evaluates scene text. `name` is shown in diagnostics; includes resolve relative to
/// the current directory.
pub fn load_source(name: &str, text: &str, options: &EvalOptions) -> Loaded {
    load_source_at(Path::new(name), name, text.to_string(), options)
}

fn load_source_at(path: &Path, name: &str, text: String, options: &EvalOptions) -> Loaded {
    // Deep but bounded recursion: run on a thread whose stack fits the configured depth.
    let stack = (64usize << 20).saturating_add(options.max_depth.saturating_mul(64 << 10));
    let stack = stack.min(2 << 30);
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("sppm-eval".into())
            .stack_size(stack)
            .spawn_scoped(s, || run(path, name, text, options))
            .ok()
            .and_then(|h| h.join().ok())
    })
    .unwrap_or_else(|| Loaded {
        scene: None,
        diagnostics: vec![Diagnostic::error(
            Span::detached(),
            "evaluation failed unexpectedly",
        )],
        sources: SourceMap::new(),
        dependencies: vec![path.to_path_buf()],
    })
}

fn run(path: &Path, name: &str, text: String, options: &EvalOptions) -> Loaded {
    let mut ev = Evaluator::new(options.clone());
    let file = ev.sources.add(path, name.to_string(), text.clone());
    ev.scene.dependencies.push(path.to_path_buf());
    ev.include_stack.push(canonical(path));
    match parse(file, &text) {
        Ok(items) => {
            let mut top = TopSink;
            ev.run_top(&items, &mut top);
            ev.finish_scene();
        }
        Err(d) => ev.errors.extend(d),
    }
    ev.finish_warnings();
    let has_errors = ev.errors.iter().any(Diagnostic::is_error);
    let mut diagnostics = ev.errors;
    diagnostics.extend(ev.warnings);
    let mut seen = std::collections::HashSet::new();
    ev.scene.dependencies.retain(|p| seen.insert(p.clone()));
    Loaded {
        dependencies: ev.scene.dependencies.clone(),
        scene: (!has_errors).then_some(ev.scene),
        diagnostics,
        sources: ev.sources,
    }
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

struct Binding {
    value: Value,
    span: Span,
    used: bool,
}

/// A macro call frame: its locals.
struct Frame {
    vars: HashMap<String, Binding>,
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
    pub(crate) assets: objects::Assets,
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
            scene: objects::empty_scene(),
            globals: HashMap::new(),
            frames: Vec::new(),
            poisoned: HashSet::new(),
            include_stack: Vec::new(),
            errors: Vec::new(),
            warnings: Vec::new(),
            warned: HashSet::new(),
            assets: objects::Assets::default(),
        }
    }

    pub(crate) fn warn(&mut self, d: Diagnostic) {
        if self.warned.insert((d.span, d.message.clone())) {
            self.warnings.push(d);
        }
    }

    /// Runs top-level items, collecting the errors of each item and going on.
    fn run_top(&mut self, items: &[Item], sink: &mut dyn Sink) {
        let mut i = 0;
        while i < items.len() {
            match self.step(items, &mut i, sink) {
                Ok(()) => {}
                Err(d) => self.errors.extend(d),
            }
        }
    }

    /// Runs a block body or directive body.
    pub(crate) fn run_items(&mut self, items: &[Item], sink: &mut dyn Sink) -> SourceResult<()> {
        let mut i = 0;
        while i < items.len() {
            self.step(items, &mut i, sink)?;
        }
        Ok(())
    }

    fn step(&mut self, items: &[Item], i: &mut usize, sink: &mut dyn Sink) -> SourceResult<()> {
        let item = &items[*i];
        *i += 1;
        match item {
            Item::Comma(_) => Ok(()),
            Item::Directive(d) => self.directive(d, sink),
            Item::Keyword(kw) => {
                let Some(spec) = sink.prop_spec(&kw.text) else {
                    let names: Vec<&str> = sink.props().iter().map(|p| p.name).collect();
                    let mut e = Error::new(format!(
                        "`{}` is not a property of {}",
                        kw.text,
                        sink.kind()
                    ))
                    .label("unknown property");
                    if let Some(s) = suggest(&kw.text, names.iter().copied()) {
                        e = e.help(format!("did you mean `{s}`?"));
                    } else if names.is_empty() {
                        e = e.help(format!("{} takes no properties", sink.kind()));
                    } else {
                        e = e.help(format!("{} accepts: {}", sink.kind(), names.join(", ")));
                    }
                    // Skip the keyword's would-be arguments.
                    while let Some(Item::Expr(_) | Item::Comma(_)) = items.get(*i) {
                        *i += 1;
                    }
                    return Err(vec![e.at(kw.span)]);
                };
                let mut args: Vec<objects::Arg> = Vec::new();
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
                            args.push(objects::Arg {
                                value,
                                span: e.span,
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

    fn directive(&mut self, d: &Directive, sink: &mut dyn Sink) -> SourceResult<()> {
        match &d.kind {
            DirectiveKind::Bind { name, value, local } => {
                let v = match self.eval(value) {
                    Ok(v) => v,
                    Err(e) => {
                        self.poisoned.insert(name.text.clone());
                        return Err(e);
                    }
                };
                self.bind(name, v, !*local);
                Ok(())
            }
            DirectiveKind::Macro(m) => {
                self.bind(&m.name, Value::Macro(m.clone()), true);
                Ok(())
            }
            DirectiveKind::If {
                branches,
                otherwise,
            } => {
                for (cond, body) in branches {
                    if self.eval(cond)?.truthy().at(cond.span)? {
                        return self.run_items(body, sink);
                    }
                }
                if let Some(body) = otherwise {
                    self.run_items(body, sink)?;
                }
                Ok(())
            }
            DirectiveKind::While { cond, body } => {
                let mut n = 0u64;
                while self.eval(cond)?.truthy().at(cond.span)? {
                    n += 1;
                    if n > self.options.max_iterations {
                        return Err(vec![self.loop_error(d.span)]);
                    }
                    self.run_items(body, sink)?;
                }
                Ok(())
            }
            DirectiveKind::For {
                var,
                from,
                to,
                step,
                body,
            } => {
                let a = self.eval(from)?.num().at(from.span)?;
                let b = self.eval(to)?.num().at(to.span)?;
                let s = match step {
                    Some(s) => self.eval(s)?.num().at(s.span)?,
                    None => 1.0,
                };
                if s == 0.0 || !s.is_finite() || !a.is_finite() || !b.is_finite() {
                    let span = step.as_ref().map_or(d.span, |s| s.span);
                    return Err(vec![
                        Error::new("a `#for` loop needs a finite, non-zero step")
                            .label("this step never ends the loop")
                            .at(span),
                    ]);
                }
                let mut n = 0u64;
                let mut x = a;
                while (s > 0.0 && x <= b + 1e-9 * s.abs()) || (s < 0.0 && x >= b - 1e-9 * s.abs()) {
                    n += 1;
                    if n > self.options.max_iterations {
                        return Err(vec![self.loop_error(d.span)]);
                    }
                    self.bind(var, Value::Num(x), false);
                    self.mark_used(&var.text);
                    self.run_items(body, sink)?;
                    x = a + n as f64 * s;
                }
                Ok(())
            }
            DirectiveKind::Include { path, path_span } => self.include(path, *path_span, sink),
        }
    }

    fn loop_error(&self, span: Span) -> Diagnostic {
        Error::new(format!(
            "loop ran more than {} iterations",
            self.options.max_iterations
        ))
        .label("this loop does not end")
        .help("check the loop condition, or raise the limit with `--max-iterations`")
        .at(span)
    }

    fn include(&mut self, path: &str, span: Span, sink: &mut dyn Sink) -> SourceResult<()> {
        let resolved = self.resolve_path(path, span);
        let canon = canonical(&resolved);
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
                Error::new("includes nested more than 64 deep").at(span),
            ]);
        }
        // Recorded before the read so that `watch` also waits for a file that is missing.
        self.scene.dependencies.push(resolved.clone());
        let text = std::fs::read_to_string(&resolved).map_err(|e| {
            vec![
                Error::new(format!("cannot read included file `{path}`: {e}"))
                    .label("not found")
                    .help(format!(
                        "the path is resolved relative to the including file: {}",
                        resolved.display()
                    ))
                    .at(span),
            ]
        })?;
        let file = self
            .sources
            .add(&resolved, resolved.display().to_string(), text.clone());
        let items = parse(file, &text)?;
        self.include_stack.push(canon);
        let r = self.run_items(&items, sink);
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

    fn call_macro(
        &mut self,
        m: &Rc<MacroDef>,
        name: &Name,
        args: &[Expr],
        call_span: Span,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        if args.len() != m.params.len() {
            let params: Vec<&str> = m.params.iter().map(|p| p.text.as_str()).collect();
            return Err(vec![
                Error::new(format!(
                    "macro `{}` takes {} argument{}, found {}",
                    name.text,
                    m.params.len(),
                    if m.params.len() == 1 { "" } else { "s" },
                    args.len()
                ))
                .label(format!(
                    "{} argument{} given",
                    args.len(),
                    if args.len() == 1 { "" } else { "s" }
                ))
                .help(format!("call it as `{}({})`", name.text, params.join(", ")))
                .at(call_span)
                .with_extra(m.name.span, "macro defined here"),
            ]);
        }
        if self.frames.len() >= self.options.max_depth {
            return Err(vec![
                Error::new(format!(
                    "macro calls nested deeper than {} (recursion without end?)",
                    self.options.max_depth
                ))
                .label(format!("call to `{}` at depth {}", name.text, self.frames.len() + 1))
                .help("make sure the recursion stops (e.g. `#if (Depth > 0)`), or raise the limit with `--max-depth`")
                .at(call_span),
            ]);
        }
        let mut vars = HashMap::new();
        for (p, a) in m.params.iter().zip(args) {
            let v = self.eval(a)?;
            vars.insert(
                p.text.clone(),
                Binding {
                    value: v,
                    span: p.span,
                    used: true,
                },
            );
        }
        self.frames.push(Frame { vars });
        let r = self.run_items(&m.body, sink);
        let frame = self.frames.pop().expect("frame");
        self.warn_unused(frame.vars);
        r.map_err(|mut ds| {
            for d in &mut ds {
                // Recursion: one entry per distinct call site.
                if d.trace.len() < 8 && d.trace.last().map(|t| t.0) != Some(call_span) {
                    d.trace
                        .push((call_span, format!("in macro `{}` called here", name.text)));
                }
            }
            ds
        })
    }

    fn bind(&mut self, name: &Name, value: Value, global: bool) {
        let b = Binding {
            value,
            span: name.span,
            used: false,
        };
        let table = if global || self.frames.is_empty() {
            &mut self.globals
        } else {
            &mut self.frames.last_mut().unwrap().vars
        };
        // Re-declaration counts the old binding as "used" for warning purposes only if it was.
        if let Some(old) = table.insert(name.text.clone(), b)
            && !old.used
            && !matches!(old.value, Value::Macro(_))
        {
            // Rebinding (e.g. a loop counter `#declare I = I + 1`) is not an unused declaration.
            if let Some(new) = table.get_mut(&name.text) {
                new.used = old.span != name.span || old.used;
            }
        }
        self.poisoned.remove(&name.text);
    }

    fn mark_used(&mut self, name: &str) {
        if let Some(b) = self.frames.last_mut().and_then(|f| f.vars.get_mut(name)) {
            b.used = true;
        } else if let Some(b) = self.globals.get_mut(name) {
            b.used = true;
        }
    }

    fn lookup_quiet(&mut self, name: &str) -> Option<Value> {
        if let Some(b) = self.frames.last_mut().and_then(|f| f.vars.get_mut(name)) {
            b.used = true;
            return Some(b.value.clone());
        }
        if let Some(b) = self.globals.get_mut(name) {
            b.used = true;
            return Some(b.value.clone());
        }
        builtins::constant(name)
    }

    fn lookup(&mut self, name: &str, span: Span) -> SourceResult<Value> {
        if let Some(v) = self.lookup_quiet(name) {
            return Ok(v);
        }
        if self.poisoned.contains(name) {
            return Err(silent());
        }
        let mut known: Vec<&str> = self.globals.keys().map(String::as_str).collect();
        if let Some(f) = self.frames.last() {
            known.extend(f.vars.keys().map(String::as_str));
        }
        known.extend(CONSTANTS);
        let mut e = Error::new(format!("unknown identifier `{name}`")).label("not declared");
        if let Some(s) = suggest(name, known) {
            e = e.help(format!("did you mean `{s}`?"));
        } else {
            e = e.help(format!("declare it first: `#declare {name} = ...`"));
        }
        Err(vec![e.at(span)])
    }

    fn warn_unused(&mut self, vars: HashMap<String, Binding>) {
        let mut unused: Vec<(String, Binding)> = vars
            .into_iter()
            .filter(|(n, b)| !b.used && !n.starts_with('_') && !b.span.is_detached())
            .collect();
        unused.sort_by_key(|(_, b)| (b.span.file.0, b.span.start));
        for (name, b) in unused {
            let what = match b.value {
                Value::Macro(_) => "macro",
                Value::Texture(_) => "texture",
                Value::Material(_) => "material",
                _ => "declaration",
            };
            self.warn(
                Diagnostic::warning(b.span, format!("unused {what} `{name}`"))
                    .with_label("declared here but never used")
                    .with_help("remove it, or start its name with `_` to keep it quietly"),
            );
        }
    }

    fn finish_warnings(&mut self) {
        let globals = std::mem::take(&mut self.globals);
        self.warn_unused(globals);
    }

    pub(crate) fn eval(&mut self, e: &Expr) -> SourceResult<Value> {
        let v = self.eval_inner(e)?;
        match &v {
            Value::Num(n) if !n.is_finite() => Err(vec![not_finite(e.span, "number")]),
            Value::Vec3(a) | Value::Color(a) if !a.is_finite() => {
                Err(vec![not_finite(e.span, "vector")])
            }
            Value::Vec2(a) if !a.is_finite() => Err(vec![not_finite(e.span, "vector")]),
            _ => Ok(v),
        }
    }

    fn eval_inner(&mut self, e: &Expr) -> SourceResult<Value> {
        Ok(match &e.kind {
            ExprKind::Number(n) => Value::Num(*n),
            ExprKind::Bool(b) => Value::Bool(*b),
            ExprKind::Str(s) => Value::Str(s.clone()),
            ExprKind::Ident(name) => self.lookup(name, e.span)?,
            ExprKind::Vector(parts) => {
                let mut xs = Vec::with_capacity(parts.len());
                for p in parts {
                    xs.push(self.eval(p)?.num().at(p.span)?);
                }
                match xs.len() {
                    2 => Value::Vec2(DVec2::new(xs[0], xs[1])),
                    3 => Value::Vec3(DVec3::new(xs[0], xs[1], xs[2])),
                    _ => Value::Array(Rc::new(xs.into_iter().map(Value::Num).collect())),
                }
            }
            ExprKind::Array(parts) => {
                let mut xs = Vec::with_capacity(parts.len());
                for p in parts {
                    xs.push(self.eval(p)?);
                }
                Value::Array(Rc::new(xs))
            }
            ExprKind::Block { kind, items } => self.eval_block(kind, items, e.span)?,
            ExprKind::Call { name, args } => {
                if let Some(Value::Macro(_)) = self.lookup_quiet(&name.text) {
                    return Err(vec![
                        Error::new(format!("macro `{}` cannot be used as a value", name.text))
                            .label("a macro call must stand alone as a statement")
                            .help("call it on its own, e.g. inside `union { ... }`")
                            .at(e.span),
                    ]);
                }
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.eval(a)?);
                }
                match builtins::call(&name.text, &vals) {
                    Some(Ok(v)) => v,
                    Some(Err((i, mut err))) => {
                        if err.label.is_empty() {
                            err.label = "invalid argument".into();
                        }
                        let span = args.get(i).map_or(e.span, |a| a.span);
                        return Err(vec![err.at(span)]);
                    }
                    None => {
                        let mut err = Error::new(format!("unknown function `{}`", name.text))
                            .label("no built-in function or macro of this name");
                        let mut cands: Vec<&str> = FUNCTIONS.to_vec();
                        let macros: Vec<String> = self
                            .globals
                            .iter()
                            .filter(|(_, b)| matches!(b.value, Value::Macro(_)))
                            .map(|(n, _)| n.clone())
                            .collect();
                        cands.extend(macros.iter().map(String::as_str));
                        if let Some(s) = suggest(&name.text, cands) {
                            err = err.help(format!("did you mean `{s}`?"));
                        }
                        return Err(vec![err.at(name.span)]);
                    }
                }
            }
            ExprKind::Unary(op, inner) => {
                let v = self.eval(inner)?;
                unary(*op, v).at(e.span)?
            }
            ExprKind::Binary(op, a, b) => {
                let va = self.eval(a)?;
                // Short-circuit logic.
                if matches!(op, BinOp::And | BinOp::Or) {
                    let x = va.truthy().at(a.span)?;
                    if (*op == BinOp::And && !x) || (*op == BinOp::Or && x) {
                        return Ok(Value::Bool(x));
                    }
                    return Ok(Value::Bool(self.eval(b)?.truthy().at(b.span)?));
                }
                let vb = self.eval(b)?;
                binary(*op, va, vb).at(e.span)?
            }
            ExprKind::Index(base, index) => {
                let vb = self.eval(base)?;
                let i = self.eval(index)?.num().at(index.span)?;
                index_value(vb, i).at(index.span)?
            }
            ExprKind::Field(base, field) => {
                let vb = self.eval(base)?;
                field_value(vb, &field.text).at(field.span)?
            }
        })
    }

    pub(crate) fn check_object_budget(&self, span: Span) -> SourceResult<()> {
        if self.scene.objects.len() >= self.options.max_objects {
            return Err(vec![
                Error::new(format!(
                    "the scene has more than {} objects",
                    self.options.max_objects
                ))
                .label("limit reached here")
                .help("is a recursion too deep?")
                .at(span),
            ]);
        }
        Ok(())
    }
}

fn not_finite(span: Span, what: &str) -> Diagnostic {
    Error::new(format!("this {what} is not finite (NaN or infinity)"))
        .label("not a finite value")
        .help("check for a division by a tiny number or an overflowing power")
        .at(span)
}

fn unary(op: UnOp, v: Value) -> Result<Value, Error> {
    Ok(match (op, v) {
        (UnOp::Pos, v @ (Value::Num(_) | Value::Vec2(_) | Value::Vec3(_) | Value::Color(_))) => v,
        (UnOp::Neg, Value::Num(n)) => Value::Num(-n),
        (UnOp::Neg, Value::Vec2(a)) => Value::Vec2(-a),
        (UnOp::Neg, Value::Vec3(a)) => Value::Vec3(-a),
        (UnOp::Neg, Value::Color(a)) => Value::Color(-a),
        (UnOp::Not, v) => Value::Bool(!v.truthy()?),
        (UnOp::Rgb, v) => Value::Color(v.color()?),
        (op, v) => {
            return Err(Error::new(format!(
                "cannot apply `{}` to {}",
                match op {
                    UnOp::Neg => "-",
                    UnOp::Pos => "+",
                    UnOp::Not => "!",
                    UnOp::Rgb => "rgb",
                },
                v.type_name()
            )));
        }
    })
}

fn binary(op: BinOp, a: Value, b: Value) -> Result<Value, Error> {
    use BinOp::*;
    use Value::*;
    let mismatch = |a: &Value, b: &Value| {
        Error::new(format!(
            "cannot apply `{}` to {} and {}",
            op.symbol(),
            a.type_name(),
            b.type_name()
        ))
        .label("type mismatch")
    };
    if matches!(op, Div) {
        let zero = match &b {
            Num(x) => *x == 0.0,
            Vec2(v) => v.x == 0.0 || v.y == 0.0,
            Vec3(v) | Color(v) => v.min_element() == 0.0 && v.abs().min_element() == 0.0,
            _ => false,
        };
        if zero {
            return Err(Error::new("division by zero").label("this divides by zero"));
        }
    }
    let arith = |x: f64, y: f64| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    let arith3 = |x: DVec3, y: DVec3| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    let arith2 = |x: DVec2, y: DVec2| match op {
        Add => x + y,
        Sub => x - y,
        Mul => x * y,
        _ => x / y,
    };
    Ok(match op {
        Add | Sub | Mul | Div => match (&a, &b) {
            (Num(x), Num(y)) => Num(arith(*x, *y)),
            (Vec3(x), Vec3(y)) => Vec3(arith3(*x, *y)),
            (Color(x), Color(y) | Vec3(y)) | (Vec3(x), Color(y)) => Color(arith3(*x, *y)),
            (Vec3(x), Num(y)) => Vec3(arith3(*x, DVec3::splat(*y))),
            (Color(x), Num(y)) => Color(arith3(*x, DVec3::splat(*y))),
            (Num(x), Vec3(y)) if matches!(op, Mul | Add) => Vec3(arith3(DVec3::splat(*x), *y)),
            (Num(x), Color(y)) if matches!(op, Mul | Add) => Color(arith3(DVec3::splat(*x), *y)),
            (Vec2(x), Vec2(y)) => Vec2(arith2(*x, *y)),
            (Vec2(x), Num(y)) => Vec2(arith2(*x, DVec2::splat(*y))),
            (Num(x), Vec2(y)) if matches!(op, Mul | Add) => Vec2(arith2(DVec2::splat(*x), *y)),
            (Str(x), Str(y)) if op == Add => Str(Rc::from(format!("{x}{y}"))),
            _ => return Err(mismatch(&a, &b)),
        },
        Lt | Le | Gt | Ge => match (&a, &b) {
            (Num(x), Num(y)) => Bool(match op {
                Lt => x < y,
                Le => x <= y,
                Gt => x > y,
                _ => x >= y,
            }),
            _ => return Err(mismatch(&a, &b).help("only numbers can be ordered")),
        },
        Eq | Ne => {
            let eq = match (&a, &b) {
                (Num(x), Num(y)) => x == y,
                (Bool(x), Bool(y)) => x == y,
                (Str(x), Str(y)) => x == y,
                (Vec2(x), Vec2(y)) => x == y,
                (Vec3(x) | Color(x), Vec3(y) | Color(y)) => x == y,
                _ => return Err(mismatch(&a, &b)),
            };
            Bool(eq == (op == Eq))
        }
        And | Or => unreachable!("short-circuited"),
    })
}

fn index_value(v: Value, i: f64) -> Result<Value, Error> {
    let len = match &v {
        Value::Array(a) => a.len(),
        Value::Vec2(_) => 2,
        Value::Vec3(_) | Value::Color(_) => 3,
        o => return Err(Error::new(format!("cannot index {}", o.type_name()))),
    };
    if i < 0.0 || i.fract() != 0.0 || i as usize >= len {
        return Err(Error::new(format!("index {i} out of range (length {len})"))
            .label("out of range")
            .help(format!("indices run from 0 to {}", len.saturating_sub(1))));
    }
    let i = i as usize;
    Ok(match v {
        Value::Array(a) => a[i].clone(),
        Value::Vec2(a) => Value::Num(a[i]),
        Value::Vec3(a) | Value::Color(a) => Value::Num(a[i]),
        _ => unreachable!(),
    })
}

fn field_value(v: Value, f: &str) -> Result<Value, Error> {
    let i = match f {
        "x" | "u" | "r" | "red" => 0,
        "y" | "v" | "g" | "green" => 1,
        "z" | "b" | "blue" => 2,
        _ => {
            return Err(Error::new(format!("unknown component `.{f}`"))
                .help("components are `.x`, `.y`, `.z` (or `.r`, `.g`, `.b`)"));
        }
    };
    index_value(v, i as f64).map_err(|_| Error::new(format!("this value has no component `.{f}`")))
}
