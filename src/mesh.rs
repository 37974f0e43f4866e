//! Triangle meshes in the model frame: positions and triangles, nothing else
//! (a silhouette needs no normals, UVs or materials).

use glam::DVec3;

/// Smallest extent of a mesh (any unit): below it, squared distances underflow.
pub const MIN_EXTENT: f64 = 1e-100;

/// A triangle mesh, model frame, node transforms already applied.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions` (counter-clockwise seen from outside,
    /// where the source says so; the silhouette does not depend on winding).
    pub triangles: Vec<[u32; 3]>,
}

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Bounds {
    /// Centre of the box.
    pub fn centre(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }
    /// Side lengths.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }
}

impl Mesh {
    /// A closed axis-aligned box of side lengths `size`, centred on the origin
    /// (8 vertices, 12 triangles, counter-clockwise seen from outside).
    pub fn cuboid(size: DVec3) -> Mesh {
        let h = size * 0.5;
        let positions = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { -h.x } else { h.x },
                    if i & 2 == 0 { -h.y } else { h.y },
                    if i & 4 == 0 { -h.z } else { h.z },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh { positions, triangles }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Bounds of all vertices (`None` for an empty mesh).
    pub fn bounds(&self) -> Option<Bounds> {
        let first = *self.positions.first()?;
        let (min, max) = self
            .positions
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        Some(Bounds { min, max })
    }

    /// The vertices used by at least one triangle.
    pub fn used_points(&self) -> Vec<DVec3> {
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &i in t {
                used[i as usize] = true;
            }
        }
        self.positions
            .iter()
            .zip(used)
            .filter_map(|(p, u)| u.then_some(*p))
            .collect()
    }

    /// The object's diameter: the largest distance between two vertices.
    /// Exact over the convex-hull candidates for small meshes; for large ones, the
    /// largest distance among extreme points along 13 directions (within about 1 %).
    pub fn diameter(&self) -> f64 {
        let pts = self.used_points();
        if pts.len() <= 3000 {
            let mut best = 0.0f64;
            for (i, a) in pts.iter().enumerate() {
                for b in &pts[i + 1..] {
                    best = best.max(a.distance_squared(*b));
                }
            }
            return best.sqrt();
        }
        let dirs = [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            DVec3::new(1., 1., 0.),
            DVec3::new(1., -1., 0.),
            DVec3::new(1., 0., 1.),
            DVec3::new(1., 0., -1.),
            DVec3::new(0., 1., 1.),
            DVec3::new(0., 1., -1.),
            DVec3::new(1., 1., 1.),
            DVec3::new(1., 1., -1.),
            DVec3::new(1., -1., 1.),
            DVec3::new(-1., 1., 1.),
        ];
        let mut ext = Vec::new();
        for d in dirs {
            let lo = pts.iter().min_by(|a, b| a.dot(d).total_cmp(&b.dot(d))).unwrap();
            let hi = pts.iter().max_by(|a, b| a.dot(d).total_cmp(&b.dot(d))).unwrap();
            ext.push(*lo);
            ext.push(*hi);
        }
        let mut best = 0.0f64;
        for e in &ext {
            for p in &pts {
                best = best.max(e.distance_squared(*p));
            }
        }
        best.sqrt()
    }

    /// Checks indices are in range and positions finite; `file` names the mesh in errors.
    pub fn validate(&self, file: &str) -> crate::Result<()> {
        let err = |p: String| crate::Error::Mesh {
            file: file.into(),
            problem: p,
        };
        if self.triangles.is_empty() {
            return Err(err("contains no triangles".into()));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(err(format!("vertex {i} has a non-finite coordinate")));
        }
        let max = crate::limits::MAX_LENGTH;
        if let Some(i) = self.positions.iter().position(|p| p.abs().max_element() > max) {
            return Err(err(format!(
                "vertex {i} has a coordinate beyond ±{max:e} ({:?}): the largest length accepted",
                self.positions[i].to_array()
            )));
        }
        let n = self.positions.len() as u32;
        if let Some(t) = self.triangles.iter().find(|t| t.iter().any(|&i| i >= n)) {
            return Err(err(format!(
                "triangle {t:?} refers to a vertex beyond the {n} vertices"
            )));
        }
        // The used vertices' extent, and the largest triangle's area against it.
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in &self.triangles {
            for &i in t {
                lo = lo.min(self.positions[i as usize]);
                hi = hi.max(self.positions[i as usize]);
            }
        }
        let extent = (hi - lo).max_element();
        let magnitude = lo.abs().max(hi.abs()).max_element();
        if !(extent > MIN_EXTENT && extent > 1e-12 * magnitude) {
            return Err(err(format!(
                "has no extent: its triangles' vertices all lie within {extent:e} of each other{}",
                if magnitude > 0.0 {
                    format!(" (at coordinates up to {magnitude:e})")
                } else {
                    String::new()
                }
            )));
        }
        // Areas relative to the extent: a collinear or zero-area mesh casts no silhouette.
        let unit = 1.0 / extent;
        let largest = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| (self.positions[i as usize] - lo) * unit);
                (b - a).cross(c - a).length()
            })
            .fold(0.0f64, f64::max);
        if largest <= 1e-12 {
            return Err(err(
                "has no area: every triangle is degenerate (collinear or repeated vertices), so it casts no silhouette"
                    .into(),
            ));
        }
        Ok(())
    }
}

impl Mesh {
    /// A coarser mesh by vertex clustering (Rossignac & Borrel, 1993): vertices are
    /// merged per cell of a `cells`³ grid over the bounds (at their mean), collapsed and
    /// repeated triangles dropped. The silhouette moves by at most about one cell, so a
    /// grid near the render's pixel size keeps low-resolution silhouettes — the
    /// orientation search's — nearly unchanged at a fraction of the triangles.
    pub fn clustered(&self, cells: u32) -> Mesh {
        let Some(b) = self.bounds() else { return self.clone() };
        let cells = cells.max(1) as f64;
        let size = b.size().max(DVec3::splat(1e-12));
        let key = |p: DVec3| {
            let q = ((p - b.min) / size * cells).floor().min(DVec3::splat(cells - 1.0));
            (q.x as u32, q.y as u32, q.z as u32)
        };
        let mut cell_of = std::collections::HashMap::new();
        let mut sums: Vec<(DVec3, u32)> = Vec::new();
        let remap: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                let id = *cell_of.entry(key(*p)).or_insert_with(|| {
                    sums.push((DVec3::ZERO, 0));
                    sums.len() as u32 - 1
                });
                sums[id as usize].0 += *p;
                sums[id as usize].1 += 1;
                id
            })
            .collect();
        let positions = sums.iter().map(|(s, n)| *s / *n as f64).collect();
        let mut seen = std::collections::HashSet::new();
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|i| remap[i as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .filter(|t| {
                let mut k = *t;
                k.sort_unstable();
                seen.insert(k)
            })
            .collect();
        Mesh { positions, triangles }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_and_diameter_of_a_cube_corner_set() {
        let m = Mesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(1., 1., 1.),
                DVec3::splat(9.),
            ],
            triangles: vec![[0, 1, 2], [1, 2, 3]],
        };
        let b = m.bounds().unwrap();
        assert_eq!(b.max, DVec3::splat(9.));
        assert!(
            (m.diameter() - 3f64.sqrt()).abs() < 1e-12,
            "unused vertex 4 must not count"
        );
        assert!(m.validate("m").is_ok());
        let bad = Mesh {
            positions: vec![DVec3::ZERO],
            triangles: vec![[0, 0, 5]],
        };
        assert!(bad.validate("m.obj").unwrap_err().to_string().contains("beyond"));
    }

    #[test]
    fn clustering_merges_close_vertices_and_keeps_bounds() {
        // Two triangles of a unit square, plus a sliver whose vertices share one cell.
        let m = Mesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(1., 1., 0.),
                DVec3::Y,
                DVec3::new(0.5, 0.5, 0.0),
                DVec3::new(0.51, 0.5, 0.0),
                DVec3::new(0.5, 0.51, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]],
        };
        let c = m.clustered(4);
        assert_eq!(c.triangles.len(), 2, "the sliver collapses");
        let b = c.bounds().unwrap();
        assert_eq!((b.min, b.max), (DVec3::ZERO, DVec3::new(1., 1., 0.)));
        c.validate("c").unwrap();
    }
}
