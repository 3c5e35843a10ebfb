//! `blob { threshold t sphere { <c>, r, strength s } cylinder { <a>, <b>, r, strength s } ... }`
//! as POV-Ray writes it. A `sphere` or `cylinder` written directly in a blob's body is a
//! component (its strength may follow the radius without the keyword, as in POV-Ray); it is
//! built as a one-component blob, and the blob gathers its components, each with its own
//! transforms.

use glam::DVec3;

use super::ObjectBuilder;
use crate::diag::{At, Error, SourceResult, short_number};
use crate::eval::value::{ObjectDef, Part, ShapeDef};
use crate::scene::{Blob, BlobComponent, MAX_BLOB_COMPONENTS, ShapeDecl};
use crate::span::Span;

const EXAMPLE: &str = "blob { threshold 0.6 sphere { <0, 0, 0>, 1, strength 1 } \
                       cylinder { <0, 0, 0>, <1, 0, 0>, 0.5, strength 1 } }";

impl ObjectBuilder {
    /// A `sphere` or `cylinder` inside a blob: one component (a blob of one).
    pub(super) fn blob_component(&self) -> SourceResult<Part> {
        let sphere = self.kind == "sphere";
        let want = if sphere { 2 } else { 3 };
        let what = if sphere {
            "`<centre>, radius, strength s`"
        } else {
            "`<end a>, <end b>, radius, strength s`"
        };
        let n = self.values.len();
        let strength_given = self.strength.is_some();
        if n < want || n > want + 1 || (n == want + 1 && strength_given) {
            return Err(vec![
                Error::new(format!(
                    "a blob's {} component takes {what}, found {n} value{}",
                    self.kind,
                    if n == 1 { "" } else { "s" }
                ))
                .label("here")
                .help(format!("e.g. `{EXAMPLE}`"))
                .at(self.span),
            ]);
        }
        if self.material.is_some() {
            return Err(vec![
                Error::new("a blob's component takes no material")
                    .label("material here")
                    .help("give the material to the whole blob")
                    .at(self.material_span),
            ]);
        }
        let point = |k: usize| -> SourceResult<DVec3> {
            let (v, s) = &self.values[k];
            let p = v.vec3().at(*s)?;
            if !p.is_finite() {
                return Err(vec![
                    Error::new("the component's point is not finite")
                        .label("here")
                        .at(*s),
                ]);
            }
            Ok(p)
        };
        let a = point(0)?;
        let b = if sphere { a } else { point(1)? };
        let (rv, rs) = &self.values[want - 1];
        let radius = rv.num().at(*rs)?;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(vec![
                Error::new(format!(
                    "a blob component's radius must be positive, found {}",
                    short_number(radius)
                ))
                .label("not a positive radius")
                .help("the radius is the component's reach: its density is 0 beyond it")
                .at(*rs),
            ]);
        }
        let (strength, sspan) = match self.strength {
            Some(s) => s,
            None if n == want + 1 => {
                let (v, s) = &self.values[want];
                (v.num().at(*s)?, *s)
            }
            None => {
                return Err(vec![
                    Error::new(format!("a blob's {} component needs a strength", self.kind))
                        .label("no strength")
                        .help(
                            "add `strength s` after the radius (negative strengths carve the \
                             blob)",
                        )
                        .at(self.span),
                ]);
            }
        };
        if !strength.is_finite() || strength == 0.0 {
            return Err(vec![
                Error::new(format!(
                    "a blob component's strength must be a non-zero number, found {}",
                    short_number(strength)
                ))
                .label("here")
                .help("positive strengths add to the field, negative ones carve it")
                .at(sspan),
            ]);
        }
        Ok(self.part(ShapeDecl::Blob(Blob {
            threshold: 1.0,
            components: vec![BlobComponent {
                a,
                b,
                radius,
                strength,
                transform: glam::DAffine3::IDENTITY,
            }],
        })))
    }

    /// A component (or a declared blob) given to a blob: its components join this blob's, with
    /// their transforms.
    pub(super) fn blob_child(&mut self, o: &ObjectDef, span: Span) -> SourceResult<()> {
        for part in &o.parts {
            let ShapeDef::Ready(ShapeDecl::Blob(b)) = &part.shape else {
                return Err(vec![
                    Error::new(
                        "a blob takes `sphere` and `cylinder` components, not other objects",
                    )
                    .label("not a component")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(span),
                ]);
            };
            if self.components.len() + b.components.len() > MAX_BLOB_COMPONENTS {
                return Err(vec![
                    Error::new(format!(
                        "a blob may have at most {MAX_BLOB_COMPONENTS} components"
                    ))
                    .label("one too many")
                    .help("split the blob, or use fewer, larger components")
                    .at(span),
                ]);
            }
            for c in &b.components {
                let mut c = c.clone();
                c.transform = part.transform * c.transform;
                self.components.push(c);
            }
        }
        Ok(())
    }

    pub(super) fn blob(&self) -> SourceResult<ShapeDecl> {
        if let Some((v, s)) = self.values.first() {
            return Err(vec![
                Error::new(format!("a blob does not take {} here", v.type_name()))
                    .label("unexpected value")
                    .help(format!(
                        "a blob takes a threshold and components: `{EXAMPLE}`"
                    ))
                    .at(*s),
            ]);
        }
        let threshold = match self.threshold {
            Some((t, s)) if !(t > 0.0 && t.is_finite()) => {
                return Err(vec![
                    Error::new(format!(
                        "a blob's threshold must be a positive number, found {}",
                        short_number(t)
                    ))
                    .label("not positive")
                    .help(
                        "the field is 0 away from the components: at a threshold of 0 or less \
                         the blob would fill all space",
                    )
                    .at(s),
                ]);
            }
            Some((t, _)) => t,
            // POV-Ray's default.
            None => 1.0,
        };
        if self.components.is_empty() {
            return Err(vec![
                Error::new("a blob needs components")
                    .label("no components")
                    .help(format!("e.g. `{EXAMPLE}`"))
                    .at(self.span),
            ]);
        }
        if !self.components.iter().any(|c| c.strength > 0.0) {
            return Err(vec![
                Error::new("every component of this blob has a negative strength: it is empty")
                    .label("no positive component")
                    .help("give at least one component a positive strength")
                    .at(self.span),
            ]);
        }
        let blob = Blob {
            threshold,
            components: self.components.clone(),
        };
        blob.check()
            .map_err(|m| vec![Error::new(m).label("here").at(self.span)])?;
        Ok(ShapeDecl::Blob(blob))
    }
}
