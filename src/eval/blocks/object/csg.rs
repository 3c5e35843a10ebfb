//! The CSG blocks `merge`, `intersection` and `difference`, `union` as a CSG child, and the
//! `inverse` flag: each builds one part holding a CSG node; lowering gives each shape in it
//! its own material (its own, else the nearest enclosing one's).

use std::rc::Rc;

use glam::DAffine3;

use super::ObjectBuilder;
use crate::diag::{Diagnostic, Error, SourceResult};
use crate::eval::Evaluator;
use crate::eval::value::{CsgDef, ObjectDef, Part, ShapeDef};
use crate::scene::{CLOSED_HELP, CsgOp, MAX_CSG_DEPTH, MAX_CSG_LEAVES, why_open};
use crate::span::Span;

/// The blocks that are CSG operations.
pub(super) fn csg_op(kind: &str) -> Option<CsgOp> {
    match kind {
        "merge" => Some(CsgOp::Merge),
        "intersection" => Some(CsgOp::Intersection),
        "difference" => Some(CsgOp::Difference),
        _ => None,
    }
}

fn leaves(part: &Part) -> usize {
    match &part.shape {
        ShapeDef::Csg(c) => c.leaves,
        _ => 1,
    }
}

fn depth(part: &Part) -> usize {
    match &part.shape {
        ShapeDef::Csg(c) => c.depth,
        _ => 0,
    }
}

/// One CSG node over `children`, checked against the tree limits.
pub(super) fn node(op: CsgOp, children: Vec<Part>, span: Span) -> SourceResult<Part> {
    let leaves = children.iter().map(leaves).sum();
    let depth = 1 + children.iter().map(depth).max().unwrap_or(0);
    if depth > MAX_CSG_DEPTH {
        return Err(vec![
            Error::new(format!(
                "CSG operations are nested more than {MAX_CSG_DEPTH} deep"
            ))
            .label("too deep")
            .help("flatten the tree: a merge, union or intersection takes any number of children")
            .at(span),
        ]);
    }
    if leaves > MAX_CSG_LEAVES {
        return Err(vec![
            Error::new(format!(
                "this {} would hold {leaves} shapes, more than {MAX_CSG_LEAVES}",
                op.name()
            ))
            .label("too many shapes")
            .help(
                "every ray into a CSG tests its shapes one by one: split it, or use `union` \
                 (flattened into the scene) where inner surfaces may stay",
            )
            .at(span),
        ]);
    }
    Ok(Part {
        shape: ShapeDef::Csg(Rc::new(CsgDef {
            op,
            children,
            leaves,
            depth,
        })),
        transform: DAffine3::IDENTITY,
        material: None,
        emission: None,
        span,
    })
}

/// An object as one closed CSG child: its one part, or a union of its parts. `op` names the
/// operation it goes into, for messages.
fn child(parts: &[Part], op: CsgOp, span: Span) -> SourceResult<Part> {
    for p in parts {
        let open = match &p.shape {
            ShapeDef::Ready(s) => why_open(s),
            _ => None,
        };
        if let Some(why) = open {
            return Err(vec![
                Error::new(format!(
                    "this shape has no inside, so it cannot be part of {}: {why}",
                    op.a_name()
                ))
                .label("not a closed shape")
                .help(CLOSED_HELP)
                .at(p.span),
            ]);
        }
        if p.emission.is_some() {
            return Err(vec![
                Error::new(format!(
                    "an area light cannot be part of a CSG {}",
                    op.name()
                ))
                .label("emissive")
                .help("place the area light beside the CSG object")
                .at(p.span),
            ]);
        }
    }
    match parts {
        [one] => Ok(one.clone()),
        _ => node(CsgOp::Union, parts.to_vec(), span),
    }
}

impl ObjectBuilder {
    /// A child object of a CSG block.
    pub(super) fn csg_child(
        &mut self,
        ev: &mut Evaluator,
        op: CsgOp,
        o: &ObjectDef,
        span: Span,
    ) -> SourceResult<()> {
        let part = child(&o.parts, op, span)?;
        let holding = self.parts.iter().map(leaves).sum();
        ev.count_parts(holding, leaves(&part), span)?;
        self.parts.push(part);
        Ok(())
    }

    /// The part of a finished CSG block.
    pub(super) fn csg_finish(&mut self, ev: &mut Evaluator, op: CsgOp) -> SourceResult<Vec<Part>> {
        if self.parts.is_empty() {
            ev.warn(
                Diagnostic::warning(self.span, format!("empty {}", op.name()))
                    .with_label("contains no objects")
                    .with_help("put objects in it, or remove it"),
            );
        }
        Ok(vec![node(op, std::mem::take(&mut self.parts), self.span)?])
    }

    /// `inverse`: the object's parts, turned inside out as one.
    pub(super) fn inverted(&self, parts: Vec<Part>) -> SourceResult<Vec<Part>> {
        let inner = child(&parts, CsgOp::Inverse, self.span)?;
        Ok(vec![node(CsgOp::Inverse, vec![inner], self.span)?])
    }
}
