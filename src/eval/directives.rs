//! Directives (`#declare`, `#local`, `#undef`, `#macro`, `#if`, `#ifdef`, `#ifndef`,
//! `#switch`, `#while`, `#for`, `#break`, `#include`, `#debug`, `#warning`, `#error`). Macro
//! calls are in `macros`.

use super::Evaluator;
use super::blocks::Sink;
use super::value::Value;
use crate::diag::{At, Diagnostic, Error, SourceResult, short_number, suggest};
use crate::span::Span;
use crate::syntax::ast::*;

impl Evaluator {
    pub(super) fn directive(&mut self, d: &Directive, sink: &mut dyn Sink) -> SourceResult<()> {
        // A directive with a body nests like a block: `#if` inside `#if` inside a recursive
        // macro counts against the same bound as blocks and calls.
        let nests = matches!(
            d.kind,
            DirectiveKind::If { .. }
                | DirectiveKind::IfDef { .. }
                | DirectiveKind::Switch { .. }
                | DirectiveKind::While { .. }
                | DirectiveKind::For { .. }
        );
        if !nests {
            return self.directive_in_place(d, sink);
        }
        self.check_nesting(d.span)?;
        self.block_depth += 1;
        let r = self.directive_in_place(d, sink);
        self.block_depth -= 1;
        r
    }

    fn directive_in_place(&mut self, d: &Directive, sink: &mut dyn Sink) -> SourceResult<()> {
        match &d.kind {
            DirectiveKind::Bind { name, value, local } => {
                Self::bindable(name)?;
                self.kind_kept(name, false)?;
                // A declared camera stands on its own (as in POV-Ray): it starts from the
                // defaults, not from the scene's camera so far.
                self.camera_from_defaults = matches!(
                    &value.kind,
                    ExprKind::Block { kind, .. } if kind.text == "camera"
                );
                self.defining =
                    matches!(value.kind, ExprKind::Function(_)).then(|| name.text.clone());
                let v = self.eval(value);
                self.camera_from_defaults = false;
                self.defining = None;
                let v = match v {
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
                Self::bindable(&m.name)?;
                self.kind_kept(&m.name, true)?;
                for p in &m.params {
                    Self::bindable(p)?;
                }
                self.bind(&m.name, Value::Macro(m.clone()), true);
                Ok(())
            }
            DirectiveKind::If {
                branches,
                otherwise,
            } => {
                for (cond, body) in branches {
                    // Each test is a step: a chain of many `#elif`s in a loop costs its length.
                    self.tick(cond.span)?;
                    if self.eval(cond)?.truthy().at(cond.span)? {
                        return self.run_items(body, sink);
                    }
                }
                if let Some(body) = otherwise {
                    self.run_items(body, sink)?;
                }
                Ok(())
            }
            DirectiveKind::IfDef {
                name,
                negate,
                body,
                otherwise,
            } => {
                if self.lookup_quiet(&name.text).is_some() != *negate {
                    self.run_items(body, sink)
                } else if let Some(body) = otherwise {
                    self.run_items(body, sink)
                } else {
                    Ok(())
                }
            }
            DirectiveKind::Undef(name) => {
                if super::scope::animation_name(&name.text).is_some() {
                    return Err(vec![
                        Error::new(format!(
                            "`{}` is a built-in animation value and cannot be undefined",
                            name.text
                        ))
                        .label("built-in name")
                        .help(
                            "remove the `#undef`: the animation values are always defined (0 in \
                             a still)",
                        )
                        .at(name.span),
                    ]);
                }
                if super::CONSTANTS.contains(&name.text.as_str()) {
                    return Err(vec![
                        Error::new(format!(
                            "`{}` is a built-in constant and cannot be undefined",
                            name.text
                        ))
                        .label("built-in name")
                        .help("remove the `#undef`: `pi`, `x`, `y` and `z` are always defined")
                        .at(name.span),
                    ]);
                }
                if !self.unbind(&name.text) {
                    let near = self
                        .may_suggest_name()
                        .then(|| suggest(&name.text, self.globals.keys().map(String::as_str)))
                        .flatten();
                    let help = match near {
                        Some(s) => format!("did you mean `{s}`?"),
                        None => "remove the `#undef`, or check the spelling of the name".into(),
                    };
                    self.warn(
                        Diagnostic::warning(
                            name.span,
                            format!("`#undef` of `{}`, which is not declared", name.text),
                        )
                        .with_label("not declared here")
                        .with_help(help),
                    );
                }
                Ok(())
            }
            DirectiveKind::Switch {
                value,
                clauses,
                otherwise,
            } => self.switch(value, clauses, otherwise.as_deref(), sink),
            DirectiveKind::Break => {
                if self.break_targets == 0 {
                    return Err(vec![
                        Error::new("`#break` outside a `#switch` or loop")
                            .label("nothing to leave here")
                            .help(
                                "`#break` ends the innermost `#switch`, `#while` or `#for` of the \
                                 same block or macro body; remove it or use `#if` instead",
                            )
                            .at(d.span),
                    ]);
                }
                self.breaking = true;
                Ok(())
            }
            DirectiveKind::Message { kind, value } => self.message(*kind, value, d.span),
            DirectiveKind::While { cond, body } => {
                let mut n = 0u64;
                while self.eval(cond)?.truthy().at(cond.span)? {
                    n += 1;
                    if n > self.options.max_iterations {
                        return Err(vec![self.loop_error(d.span)]);
                    }
                    self.tick(d.span)?;
                    if self.run_breakable(body, sink)? {
                        break;
                    }
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
                Self::bindable(var)?;
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
                            .help("give a finite step other than 0, e.g. `#for (I, 0, 10, 1)`")
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
                    if self.run_breakable(body, sink)? {
                        break;
                    }
                    x = a + n as f64 * s;
                }
                Ok(())
            }
            DirectiveKind::Include { path, path_span } => self.include(path, *path_span, sink),
        }
    }

    /// Runs the body of a `#switch` clause or loop iteration; `true` when a `#break` ended it.
    fn run_breakable(&mut self, body: &[Item], sink: &mut dyn Sink) -> SourceResult<bool> {
        self.break_targets += 1;
        let r = self.run_items(body, sink);
        self.break_targets -= 1;
        r?;
        Ok(std::mem::take(&mut self.breaking))
    }

    /// Runs `body` as the body of a block or macro: a `#break` there cannot leave a `#switch`
    /// or loop around the block or call.
    pub(crate) fn run_body(&mut self, body: &[Item], sink: &mut dyn Sink) -> SourceResult<()> {
        let outer = std::mem::take(&mut self.break_targets);
        let r = self.run_items(body, sink);
        self.break_targets = outer;
        r
    }

    /// `#switch`, as in POV-Ray: the clauses are tested in order until one matches (its
    /// `#case` value equals the switch value within 1e-10, or its `#range (lo, hi)` holds it,
    /// inclusive); from there every body runs, `#else`'s included, until a `#break`. `#else`
    /// also runs when nothing matched.
    fn switch(
        &mut self,
        value: &Expr,
        clauses: &[Clause],
        otherwise: Option<&[Item]>,
        sink: &mut dyn Sink,
    ) -> SourceResult<()> {
        let v = self.eval(value)?.num().at(value.span)?;
        // Once a clause matched, the following clauses (and `#else`) run without their tests
        // until a `#break`: POV-Ray's (and C's) fall-through.
        let mut falling = false;
        for clause in clauses {
            // (A clause's test is not evaluated once falling through.)
            falling = falling || self.clause_matches(&clause.test, v)?;
            if falling && self.run_breakable(&clause.body, sink)? {
                return Ok(());
            }
        }
        // Reached without a `#break`: nothing matched, or the last clause fell through.
        match otherwise {
            Some(body) => self.run_breakable(body, sink).map(|_| ()),
            None => Ok(()),
        }
    }

    /// Whether `#switch`'s value `v` matches a `#case` or `#range` clause.
    fn clause_matches(&mut self, test: &ClauseTest, v: f64) -> SourceResult<bool> {
        // Each test is a step: a `#switch` of many clauses in a loop costs its length.
        let span = match test {
            ClauseTest::Case(e) | ClauseTest::Range(e, _) => e.span,
        };
        self.tick(span)?;
        Ok(match test {
            ClauseTest::Case(e) => {
                (self.eval(e)?.num().at(e.span)? - v).abs() < super::expr::EQUAL_WITHIN
            }
            ClauseTest::Range(lo, hi) => {
                let a = self.eval(lo)?.num().at(lo.span)?;
                let b = self.eval(hi)?.num().at(hi.span)?;
                if a > b {
                    // Would never match: a mistake, as with `clamp`'s bounds.
                    let (a, b) = (short_number(a), short_number(b));
                    return Err(vec![
                        Error::new(format!("`#range` bounds are reversed ({a} > {b})"))
                            .label("the lower bound comes first")
                            .help(format!(
                                "write `#range ({b}, {a})`: a reversed range never matches"
                            ))
                            .at(lo.span.join(hi.span)),
                    ]);
                }
                a <= v && v <= b
            }
        })
    }

    /// `#debug`, `#warning` and `#error`: a message at the directive's span. `#error` stops
    /// the load.
    fn message(&mut self, kind: MessageKind, value: &Expr, span: Span) -> SourceResult<()> {
        let v = self.eval(value)?;
        // A string is cut to what a diagnostic keeps before it is copied (see `clip_text`).
        let text = match &v {
            Value::Str(s) => Some(crate::diag::clip_text(s)),
            v => v.show(),
        };
        // POV-Ray's messages end their lines with `\n`; a diagnostic is a line of its own.
        let text = text.map(|t| match t.strip_suffix('\n') {
            Some(line) => line.to_string(),
            None => t,
        });
        let text = match text {
            Some(t) => t,
            None => {
                return Err(vec![
                    Error::new(format!("a message is a string, found {}", v.type_name()))
                        .label("not a string")
                        .help("write a string, e.g. `#debug \"size: \" + str(Size)`")
                        .at(value.span),
                ]);
            }
        };
        match kind {
            MessageKind::Debug | MessageKind::Warning => {
                // `#debug` and `#warning` together: at most MAX_MESSAGES per load.
                self.messages += 1;
                let d = if kind == MessageKind::Debug {
                    Diagnostic::note(span, text).with_label("`#debug`")
                } else {
                    Diagnostic::warning(span, text).with_label("`#warning`")
                };
                if self.messages <= super::MAX_MESSAGES {
                    if kind == MessageKind::Debug {
                        self.warnings.push(d);
                    } else {
                        self.warn(d);
                    }
                } else if self.messages == super::MAX_MESSAGES + 1 {
                    self.warnings.push(
                        Diagnostic::note(
                            span,
                            format!(
                                "more than {} `#debug` and `#warning` messages: the rest are not \
                                 shown",
                                super::MAX_MESSAGES
                            ),
                        )
                        .with_label("this one and the later ones"),
                    );
                }
                Ok(())
            }
            MessageKind::Error => {
                // Every later step fails silently: the load ends with this one error.
                self.exhausted = true;
                Err(vec![
                    Diagnostic::error(span, text).with_label("`#error`: the load stops here"),
                ])
            }
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
}
