//! Macro calls, as in POV-Ray: a macro's body stands where the call stands. Called as a
//! statement (`Row(3)` in a `union`), the body's items go to the body around the call: its
//! objects, or a value that body takes (`sphere { <0, 0, 0>, Radius(3) }`). Called where a
//! value stands (`#declare R = Radius(3);`, `<Lerp(0, 1, T), 0, 0>`), the body runs the same
//! way in the macro's own scope and must yield exactly one value: after any directives
//! (`#local`, `#if`, ...), one expression, an object, a material, ...; an `#if` may choose it,
//! so a value macro can recurse.

use std::collections::HashMap;
use std::rc::Rc;

use super::Evaluator;
use super::args::Arg;
use super::blocks::{Sink, UNEXPECTED_VALUE};
use super::props::PropSpec;
use super::scope::{Binding, Frame};
use super::value::Value;
use crate::diag::{Diagnostic, Error, SourceResult};
use crate::span::Span;
use crate::syntax::ast::*;

impl Evaluator {
    /// A macro call standing as a statement: the items of its body go to `sink`.
    pub(super) fn call_macro(
        &mut self,
        m: &Rc<MacroDef>,
        name: &Name,
        args: &[Expr],
        call_span: Span,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        let mut call = StatementCall {
            inner: sink,
            m,
            call_span,
        };
        self.run_macro(m, name, args, call_span, &mut call)
    }

    /// A macro call where a value stands: the one value its body yields.
    pub(super) fn call_macro_value(
        &mut self,
        m: &Rc<MacroDef>,
        name: &Name,
        args: &[Expr],
        call_span: Span,
    ) -> SourceResult<Value> {
        let mut sink = ValueSink { m, first: None };
        self.run_macro(m, name, args, call_span, &mut sink)?;
        match sink.first {
            Some((v, _)) => Ok(v),
            None => Err(vec![
                Error::new(format!("macro `{}` yields no value", name.text))
                    .label("used as a value here")
                    .help(format!(
                        "`{n}` is a statement macro (its body ends in no value): call it on its \
                         own, `{n}({p})`, or inside `union {{ {n}({p}) }}` to use its objects as \
                         one; a macro used as a value ends its body in one value, e.g. `#macro \
                         Half(X) X / 2 #end` then `#declare H = Half(3);`",
                        n = name.text,
                        p = params(m)
                    ))
                    .at(call_span)
                    .with_extra(m.name.span, "macro defined here"),
            ]),
        }
    }

    /// Binds the arguments in a new frame and runs the body into `sink`, within the depth,
    /// nesting and step budgets; errors inside get the call in their trace.
    fn run_macro(
        &mut self,
        m: &Rc<MacroDef>,
        name: &Name,
        args: &[Expr],
        call_span: Span,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        if args.len() != m.params.len() {
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
                .help(format!("call it as `{}({})`", name.text, params(m)))
                .at(call_span)
                .with_extra(m.name.span, "macro defined here"),
            ]);
        }
        self.charge(args.len() as u64 * super::STEPS_PER_ELEMENT, call_span)?;
        let depth = self.macro_depth();
        if depth >= self.max_macro_depth() {
            let limit = self.max_macro_depth();
            let label = format!("call to `{}` at depth {}", name.text, depth + 1);
            let e = match self.stack_limit() {
                Some((why, help)) if limit < self.options.max_depth => Error::new(format!(
                    "macro calls nested deeper than {limit} (lowered from `--max-depth` {}: {why})",
                    self.options.max_depth
                ))
                .help(help),
                _ => Error::new(format!(
                    "macro calls nested deeper than {limit} (recursion without end?)"
                ))
                .help(
                    "make sure the recursion stops (e.g. `#if (Depth > 0)`), or raise the \
                     limit with `--max-depth`",
                ),
            };
            return Err(vec![e.label(label).at(call_span)]);
        }
        self.check_nesting(call_span)?;
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
        self.frames.push(Frame { vars, file: false });
        let r = self.run_body(&m.body, sink);
        let frame = self.frames.pop().expect("frame");
        self.warn_unused(frame.vars);
        r.map_err(|mut ds| {
            for d in &mut ds {
                // Recursion: one entry per distinct call site (none where the error itself
                // points at the call).
                if d.trace.len() < 8
                    && d.span != call_span
                    && d.trace.last().map(|t| t.0) != Some(call_span)
                {
                    d.trace
                        .push((call_span, format!("in macro `{}` called here", name.text)));
                }
            }
            ds
        })
    }
}

/// `A, B`: a macro's parameters as a call writes them.
fn params(m: &MacroDef) -> String {
    let ps: Vec<&str> = m.params.iter().map(|p| p.text.as_str()).collect();
    ps.join(", ")
}

/// Whether `span` lies in the body of `m` (a value written there, not in a macro it calls).
fn in_body(m: &MacroDef, span: Span) -> bool {
    match (m.body.first(), m.body.last()) {
        (Some(a), Some(b)) => {
            let body = a.span().join(b.span());
            body.file == span.file && body.start <= span.start && span.end <= body.end
        }
        _ => false,
    }
}

/// The body around a macro called as a statement, seen through the call: a value of the
/// macro's body that the body around refuses (`Radius(3)` alone at the top level) is reported
/// as a value macro used as a statement.
struct StatementCall<'a, 'b> {
    inner: &'a mut (dyn Sink + 'b),
    m: &'a MacroDef,
    call_span: Span,
}

impl Sink for StatementCall<'_, '_> {
    fn kind(&self) -> String {
        self.inner.kind()
    }
    fn props(&self) -> &'static [PropSpec] {
        self.inner.props()
    }
    fn prop_spec(&self, name: &str) -> Option<&'static PropSpec> {
        self.inner.prop_spec(name)
    }
    fn property(&mut self, ev: &mut Evaluator, kw: &Name, args: Vec<Arg>) -> SourceResult<()> {
        self.inner.property(ev, kw, args)
    }
    fn positional(&mut self, ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        // Objects, lights and the like stand as statements: their refusal is the body's own.
        let plain = !matches!(
            v,
            Value::Object(_)
                | Value::Light(_)
                | Value::Camera(_)
                | Value::Settings(_)
                | Value::Environment(_)
        );
        let what = v.type_name();
        let kind = self.inner.kind();
        self.inner
            .positional(ev, v, span)
            .map_err(|ds| match &ds[..] {
                [d] if plain
                    && d.span == span
                    && d.label == UNEXPECTED_VALUE
                    && in_body(self.m, span) =>
                {
                    vec![used_as_statement(self.m, what, &kind, self.call_span, span)]
                }
                _ => ds,
            })
    }
    fn positional_help(&self) -> &'static str {
        self.inner.positional_help()
    }
}

/// A value macro called as a statement where its value cannot stand.
fn used_as_statement(m: &MacroDef, what: &str, kind: &str, call: Span, value: Span) -> Diagnostic {
    let n = &m.name.text;
    Error::new(format!(
        "macro `{n}` yields {what}, which {kind} does not take here"
    ))
    .label("a value macro used as a statement")
    .help(format!(
        "`{n}` is a value macro: use it where a value stands, e.g. `#declare V = {n}({p});` or \
         as a property's value; a macro called as a statement declares objects or statements \
         in its body, e.g. `#macro Ball(R) sphere {{ <0, 0, 0>, R }} #end` then `Ball(1)` on \
         its own",
        p = params(m)
    ))
    .at(call)
    .with_extra(value, format!("the value `{n}` yields"))
}

/// The body of a macro called where a value stands: takes its one value.
struct ValueSink<'a> {
    m: &'a MacroDef,
    first: Option<(Value, Span)>,
}

impl Sink for ValueSink<'_> {
    fn kind(&self) -> String {
        format!("macro `{}` used as a value", self.m.name.text)
    }
    fn props(&self) -> &'static [PropSpec] {
        &[]
    }
    fn property(&mut self, _ev: &mut Evaluator, kw: &Name, _args: Vec<Arg>) -> SourceResult<()> {
        // (Not reached: with no properties, a keyword is refused before it gets here.)
        Err(vec![
            Error::new(format!("`{}` is not a value", kw.text))
                .label("a property")
                .at(kw.span),
        ])
    }
    fn positional(&mut self, _ev: &mut Evaluator, v: Value, span: Span) -> SourceResult<()> {
        if let Some((_, first)) = &self.first {
            let n = &self.m.name.text;
            return Err(vec![
                Error::new(format!("macro `{n}` yields more than one value"))
                    .label(format!("a second value, {}", v.type_name()))
                    .help(format!(
                        "a macro used as a value yields one value (its body: any directives, \
                         then one expression or block); to use several objects as one, wrap \
                         the call: `union {{ {n}({}) }}`",
                        params(self.m)
                    ))
                    .at(span)
                    .with_extra(*first, "the first value"),
            ]);
        }
        self.first = Some((v, span));
        Ok(())
    }
}
