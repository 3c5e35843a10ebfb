//! Directives (`#declare`, `#local`, `#macro`, `#if`, `#while`, `#for`, `#include`) and macro
//! calls.

use std::collections::HashMap;
use std::rc::Rc;

use super::Evaluator;
use super::blocks::Sink;
use super::scope::{Binding, Frame};
use super::value::Value;
use crate::diag::{At, Diagnostic, Error, SourceResult};
use crate::span::Span;
use crate::syntax::ast::*;

impl Evaluator {
    pub(super) fn directive(&mut self, d: &Directive, sink: &mut dyn Sink) -> SourceResult<()> {
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
                    self.tick(d.span)?;
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
                    self.tick(d.span)?;
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

    pub(super) fn call_macro(
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
}
