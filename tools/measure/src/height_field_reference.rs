//! A slow reference intersector for `height_field`: every triangle of the closed surface
//! (the product's own list, [`HeightField::surface_triangles`], which defines the shape) tested
//! one by one with the same watertight triangle test, the nearest hit kept. What it checks in
//! the product is the traversal: a hierarchy that prunes a cell it should have tested shows as
//! a miss or a farther hit.

use glam::DVec3;
use sppm_lang::internals::shapes::height_field::{Face, HeightField, WatertightRay};

pub struct RefHeightField {
    triangles: Vec<([DVec3; 3], Face)>,
}

impl RefHeightField {
    pub fn new(field: &HeightField) -> Self {
        Self {
            triangles: field.surface_triangles(),
        }
    }

    /// Triangles tested per ray.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The nearest hit with `t > lo`: its `t` and face.
    pub fn nearest(&self, o: DVec3, d: DVec3, lo: f64) -> Option<(f64, Face)> {
        let r = WatertightRay::new(o, d);
        let mut best: Option<(f64, Face)> = None;
        for (tri, face) in &self.triangles {
            let [a, b, c] = tri.map(|p| r.vertex(p));
            if let Some((t, _)) = r.hit(a, b, c)
                && t > lo
                && best.is_none_or(|(bt, _)| t < bt)
            {
                best = Some((t, *face));
            }
        }
        best
    }
}
