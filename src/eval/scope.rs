//! Scopes: global and macro-local bindings, lookups with "did you mean", and the warnings for
//! unused declarations.

use std::collections::HashMap;

use super::builtins::{self, CONSTANTS};
use super::value::Value;
use super::{Evaluator, silent};
use crate::diag::{Diagnostic, Error, SourceResult, suggest};
use crate::span::Span;
use crate::syntax::ast::Name;

pub(super) struct Binding {
    pub(super) value: Value,
    pub(super) span: Span,
    pub(super) used: bool,
}

/// A frame of locals: a macro call's (its parameters and `#local`s), or an included file's
/// (the `#local`s at its top level, gone when the file ends).
pub(super) struct Frame {
    pub(super) vars: HashMap<String, Binding>,
    /// An included file's frame, not a macro call's.
    pub(super) file: bool,
}

/// What built-in animation name `name` is (`clock`, `frame_number`, ...), if it is one.
pub(super) fn animation_name(name: &str) -> Option<&'static str> {
    crate::scene::ANIMATION_NAMES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, what)| *what)
}

impl Evaluator {
    /// The frame that holds `name` among those a lookup sees, innermost first: the current
    /// macro call's, and the frames of the included files being run (each include's top-level
    /// `#local`s); not the frames of the macro calls further out.
    fn local_frame(&self, name: &str) -> Option<usize> {
        let mut in_macro = false;
        for (i, f) in self.frames.iter().enumerate().rev() {
            if !f.file {
                if in_macro {
                    continue;
                }
                in_macro = true;
            }
            if f.vars.contains_key(name) {
                return Some(i);
            }
        }
        None
    }

    /// How many macro calls are running (the recursion depth).
    pub(super) fn macro_depth(&self) -> usize {
        self.frames.iter().filter(|f| !f.file).count()
    }

    pub(super) fn bind(&mut self, name: &Name, value: Value, global: bool) {
        let b = Binding {
            value,
            span: name.span,
            used: false,
        };
        // `#local` binds in the innermost frame: the current macro call's, or the included
        // file's being run; at the main file's top level, globally.
        let table = match self.frames.last_mut() {
            Some(f) if !global => &mut f.vars,
            _ => &mut self.globals,
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

    /// Refuses to bind a built-in constant's name (`x`, `y`, `z`, `pi`), as POV-Ray does: a
    /// `#for (x, ...)` would silently change every later `x` (a `scale 1 + x` scaling by the
    /// loop's last value).
    pub(super) fn bindable(name: &Name) -> SourceResult<()> {
        if let Some(what) = animation_name(&name.text) {
            return Err(vec![
                Error::new(format!(
                    "`{}` is a built-in animation value ({what}) and cannot be declared",
                    name.text
                ))
                .label("built-in name")
                .help(
                    "the animation values come from the frame being rendered (`render --frames`, \
                     `settings { frames ... }`); choose another name for a value of your own, \
                     e.g. `#declare T = clock * 2;`",
                )
                .at(name.span),
            ]);
        }
        if !CONSTANTS.contains(&name.text.as_str()) {
            return Ok(());
        }
        let what = match builtins::constant(&name.text) {
            Some(Value::Vec3(v)) => format!("the vector <{}, {}, {}>", v.x, v.y, v.z),
            _ => "the number π".to_string(),
        };
        Err(vec![
            Error::new(format!(
                "`{}` is a built-in constant ({what}) and cannot be declared",
                name.text
            ))
            .label("built-in name")
            .help(format!(
                "choose another name, e.g. `{}1` or `{}`",
                name.text.to_uppercase(),
                name.text.to_uppercase()
            ))
            .at(name.span),
        ])
    }

    /// Removes a binding (the innermost a lookup sees: a local, else the global one); `false`
    /// when there was none.
    pub(super) fn unbind(&mut self, name: &str) -> bool {
        if let Some(i) = self.local_frame(name) {
            return self.frames[i].vars.remove(name).is_some();
        }
        self.globals.remove(name).is_some()
    }

    /// The binding a lookup of `name` finds (a local, else the global one).
    fn binding_mut(&mut self, name: &str) -> Option<&mut Binding> {
        match self.local_frame(name) {
            Some(i) => self.frames[i].vars.get_mut(name),
            None => self.globals.get_mut(name),
        }
    }

    /// What a lookup of `name` would find, without marking it used: whether it is a macro, and
    /// where it was bound.
    pub(super) fn bound_kind(&self, name: &str) -> Option<(bool, Span)> {
        let b = match self.local_frame(name) {
            Some(i) => self.frames[i].vars.get(name),
            None => self.globals.get(name),
        }?;
        Some((matches!(b.value, Value::Macro(_)), b.span))
    }

    /// Refuses to bind `name` as a value where it names a macro, or as a macro where it names
    /// a value (POV-Ray refuses both): the silent replacement turned every later call of the
    /// macro into an error about calling a number, far from its cause. A macro may be
    /// redefined, and `#undef` frees a name.
    pub(super) fn kind_kept(&self, name: &Name, macro_: bool) -> SourceResult<()> {
        match self.bound_kind(&name.text) {
            Some((was_macro, at)) if was_macro != macro_ => {
                let (message, label, help) = if was_macro {
                    (
                        format!(
                            "`{}` is a macro and cannot also be declared as a value",
                            name.text
                        ),
                        "declared as a value here",
                        format!(
                            "give the value another name, or `#undef {}` first to drop the macro",
                            name.text
                        ),
                    )
                } else {
                    (
                        format!(
                            "`{}` is declared as a value and cannot also name a macro",
                            name.text
                        ),
                        "a macro of that name",
                        format!(
                            "give the macro another name, or `#undef {}` first to drop the value",
                            name.text
                        ),
                    )
                };
                let before = if was_macro { "the macro" } else { "the value" };
                Err(vec![
                    Error::new(message)
                        .label(label)
                        .help(help)
                        .at(name.span)
                        .with_extra(at, format!("{before} is defined here")),
                ])
            }
            _ => Ok(()),
        }
    }

    pub(super) fn mark_used(&mut self, name: &str) {
        if let Some(b) = self.binding_mut(name) {
            b.used = true;
        }
    }

    pub(super) fn lookup_quiet(&mut self, name: &str) -> Option<Value> {
        if let Some(b) = self.binding_mut(name) {
            b.used = true;
            return Some(b.value.clone());
        }
        if let Some(v) = crate::scene::animation_value(name, self.options.frame.as_ref()) {
            self.animated = true;
            return Some(if name == "clock_on" {
                Value::Bool(v != 0.0)
            } else {
                Value::Num(v)
            });
        }
        builtins::constant(name)
    }

    /// The names a lookup can find here: globals, the locals it sees, constants.
    fn known_names(&self) -> Vec<&str> {
        let mut known: Vec<&str> = self.globals.keys().map(String::as_str).collect();
        let mut in_macro = false;
        for f in self.frames.iter().rev() {
            if !f.file {
                if in_macro {
                    continue;
                }
                in_macro = true;
            }
            known.extend(f.vars.keys().map(String::as_str));
        }
        known.extend(CONSTANTS);
        known.extend(crate::scene::ANIMATION_NAMES.iter().map(|(n, _)| *n));
        known
    }

    /// Whether an undeclared `name` is close to a name a lookup can find (a misspelt one);
    /// past [`super::MAX_NAME_SUGGESTIONS`] searches, taken to be.
    pub(super) fn near_a_known_name(&mut self, name: &str) -> bool {
        !self.may_suggest_name() || suggest(name, self.known_names()).is_some()
    }

    pub(super) fn lookup(&mut self, name: &str, span: Span) -> SourceResult<Value> {
        if let Some(v) = self.lookup_quiet(name) {
            return Ok(v);
        }
        if self.poisoned.contains(name) {
            return Err(silent());
        }
        let mut e = Error::new(format!("unknown identifier `{name}`")).label("not declared");
        if name == "area_light" {
            // `light_source { <p> color C area_light <u>, <v>, n, m }`
            e = Error::new("`area_light` without a body")
                .label("a block name, but no `{ ... }` follows")
                .help(
                    "POV-Ray's `light_source { ... area_light <u>, <v>, n, m }` is a block of \
                     its own here: `area_light { quad { <corner>, <u>, <v> } radiance rgb \
                     <...> }` (one-sided: it shines along u × v)",
                );
        } else if name == "spotlight" {
            // `light_source { <p> color C spotlight point_at <t> ... }`
            e = Error::new("`spotlight` without a body")
                .label("a block name, but no `{ ... }` follows")
                .help(
                    "POV-Ray's `light_source { <p> ... spotlight point_at <t> }` is a block of \
                     its own here: `spotlight { <p> point_at <t> intensity rgb <...> angle a \
                     falloff f }`",
                );
        } else if super::blocks::is_block_name(name) {
            // `material Shiny`: a block written without its braces.
            e = Error::new(format!("`{name}` without a body"))
                .label("a block name, but no `{ ... }` follows")
                .help(format!(
                    "a block's contents go in braces: `{name} {{ ... }}`{}",
                    if name == "material" {
                        ", e.g. `material { Name }` for a declared material `Name`"
                    } else {
                        ""
                    }
                ));
        } else if let Some(hint) = crate::syntax::povray_hint(name, "") {
            e = e.help(hint);
        } else if let Some(file) = super::stdlib::declaring(name) {
            e = e.help(format!(
                "`{name}` is declared in the standard library: add `#include \"{file}\"`"
            ));
        } else if let Some(s) = self
            .may_suggest_name()
            .then(|| suggest(name, self.known_names()))
            .flatten()
        {
            e = e.help(format!("did you mean `{s}`?"));
        } else {
            e = e.help(format!("declare it first: `#declare {name} = ...`"));
        }
        Err(vec![e.at(span)])
    }

    pub(super) fn warn_unused(&mut self, vars: HashMap<String, Binding>) {
        let mut unused: Vec<(String, Binding)> = vars
            .into_iter()
            .filter(|(n, b)| {
                !b.used
                    && !n.starts_with('_')
                    && !b.span.is_detached()
                    && Some(b.span.file) == self.main_file
            })
            .collect();
        if unused.is_empty() {
            return;
        }
        // A name the sources mention again is used where this evaluation did not go (an `#if`
        // branch not taken, a macro not called): removing it would break the scene once it
        // does. (A mention in a comment or a string counts too: the warning stays true.)
        let files = self.sources.files().len();
        if self.mentions.as_ref().is_none_or(|(n, _)| *n != files) {
            self.mentions = Some((files, word_counts(self.sources.files())));
        }
        if let Some((_, counts)) = &self.mentions {
            unused.retain(|(name, _)| counts.get(name).is_none_or(|&c| c <= 1));
        }
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

    pub(super) fn finish_warnings(&mut self) {
        let globals = std::mem::take(&mut self.globals);
        self.warn_unused(globals);
    }
}

/// How often each name-like word (`[A-Za-z_][A-Za-z0-9_]*`) occurs in `files`.
fn word_counts(files: &[crate::diag::SourceFile]) -> HashMap<String, u32> {
    let mut counts: HashMap<String, u32> = HashMap::new();
    for f in files {
        let b = f.text.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if b[i].is_ascii_alphabetic() || b[i] == b'_' {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                // (A new String only for a word not seen before.)
                let word = &f.text[start..i];
                match counts.get_mut(word) {
                    Some(c) => *c += 1,
                    None => {
                        counts.insert(word.to_string(), 1);
                    }
                }
            } else if b[i].is_ascii_digit() {
                // A number's digits and exponent are not a name (`1e5`, `2x`).
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
            } else {
                i += 1;
            }
        }
    }
    counts
}
