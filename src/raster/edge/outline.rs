//! The outline as samples: after a render, points spaced along the accepted outline
//! edges (the silhouette's boundary), each with its outward normal, its edge and the
//! length of outline it stands for. The uncertainty of a fit and the next-best-view
//! ranking integrate over the outline with these (`crate::uncertainty`).
//!
//! A sample is the point `q = a + t·(b − a)` at the middle of one of `n = ⌈|b − a|/
//! spacing⌉` equal pieces of a candidate outline edge a → b (module doc of `edge.rs`,
//! step 3), kept when it lies on the canvas and `q + 10⁻⁶·n_out` is inside no present
//! face: exactly the boundary of the projected surface. (The renderer's accept test,
//! a probe one pixel out against the pixel coverage, also accepts contour chains
//! just inside the outline where a fold runs along it; the soft silhouette takes the
//! nearest edge per pixel so it does not mind, but an integral over the outline
//! would count those stretches twice.)

use super::candidates::Accept;
use super::EdgeSilhouette;
use crate::raster::project::Projected;
use glam::DVec2;

/// Side of the cells present faces are binned into for the inside test, pixels.
const CELL: f64 = 4.0;

/// A point of the rendered outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutlineSample {
    /// Position, canvas pixels (pixel centres at integers).
    pub pos: DVec2,
    /// Unit outward normal.
    pub normal: DVec2,
    /// The edge's ends (original vertex indices): `pos = (1 − t)·uv_a + t·uv_b`.
    pub a: u32,
    /// Second end.
    pub b: u32,
    /// Parameter along a → b.
    pub t: f64,
    /// Outline length this sample stands for, pixels.
    pub length: f64,
}

impl EdgeSilhouette {
    /// Samples of the outline of the last render (of `proj` and `triangles`, as
    /// given to [`EdgeSilhouette::render`]), about `spacing` pixels apart (module
    /// doc), written into `out`.
    pub fn outline_samples(
        &self,
        proj: &Projected,
        triangles: &[[u32; 3]],
        spacing: f64,
        out: &mut Vec<OutlineSample>,
    ) {
        out.clear();
        if triangles.len() != self.face_sign.len() {
            return;
        }
        let spacing = if spacing.is_finite() && spacing > 0.0 {
            spacing
        } else {
            0.5
        };
        let (wm, hm) = (self.width as f64 - 0.5, self.height as f64 - 0.5);
        let faces = FaceGrid::new(&self.face_sign, &proj.uv, triangles, self.width, self.height);
        for e in &self.edges {
            if e.accept == Accept::Never || !e.len.is_finite() {
                continue;
            }
            let n = (e.len / spacing).ceil().clamp(1.0, 1e6) as usize;
            let length = e.len / n as f64;
            for k in 0..n {
                let t = (k as f64 + 0.5) / n as f64;
                let q = e.a + e.dir * t;
                if !(q.x >= -0.5 && q.y >= -0.5 && q.x < wm && q.y < hm) {
                    continue;
                }
                if faces.covers(q + e.out * 1e-6, &proj.uv, triangles) {
                    continue;
                }
                out.push(OutlineSample {
                    pos: q,
                    normal: e.out,
                    a: e.ia,
                    b: e.ib,
                    t,
                    length,
                });
            }
        }
    }
}

/// Present faces binned by their boxes into cells of [`CELL`] pixels over the canvas.
struct FaceGrid {
    cols: usize,
    rows: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl FaceGrid {
    fn new(sign: &[i8], uv: &[DVec2], triangles: &[[u32; 3]], width: u32, height: u32) -> FaceGrid {
        let cols = (f64::from(width) / CELL).ceil() as usize + 1;
        let rows = (f64::from(height) / CELL).ceil() as usize + 1;
        let cell_range = |lo: f64, hi: f64, n: usize| -> Option<(usize, usize)> {
            let (a, b) = (((lo + 0.5) / CELL).floor(), ((hi + 0.5) / CELL).floor());
            if !(b >= 0.0 && a < n as f64) {
                return None;
            }
            Some((a.max(0.0) as usize, (b as usize).min(n - 1)))
        };
        let boxes: Vec<Option<(usize, usize, usize, usize)>> = triangles
            .iter()
            .zip(sign)
            .map(|(t, &s)| {
                if s == 0 {
                    return None;
                }
                let [a, b, c] = t.map(|i| uv[i as usize]);
                let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
                let (x0, x1) = cell_range(lo.x, hi.x, cols)?;
                let (y0, y1) = cell_range(lo.y, hi.y, rows)?;
                Some((x0, x1, y0, y1))
            })
            .collect();
        let mut count = vec![0u32; cols * rows + 1];
        for &(x0, x1, y0, y1) in boxes.iter().flatten() {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    count[y * cols + x + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let start = count.clone();
        let mut items = vec![0u32; *count.last().unwrap_or(&0) as usize];
        for (f, b) in boxes.iter().enumerate() {
            if let Some((x0, x1, y0, y1)) = *b {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let c = &mut count[y * cols + x];
                        items[*c as usize] = f as u32;
                        *c += 1;
                    }
                }
            }
        }
        FaceGrid {
            cols,
            rows,
            start,
            items,
        }
    }

    /// Whether `p` is strictly inside a present face.
    fn covers(&self, p: DVec2, uv: &[DVec2], triangles: &[[u32; 3]]) -> bool {
        let (cx, cy) = (((p.x + 0.5) / CELL).floor(), ((p.y + 0.5) / CELL).floor());
        if !(cx >= 0.0 && cy >= 0.0 && (cx as usize) < self.cols && (cy as usize) < self.rows) {
            return false;
        }
        let c = cy as usize * self.cols + cx as usize;
        self.items[self.start[c] as usize..self.start[c + 1] as usize]
            .iter()
            .any(|&f| {
                let [a, b, c] = triangles[f as usize].map(|i| uv[i as usize]);
                let d = [
                    (b - a).perp_dot(p - a),
                    (c - b).perp_dot(p - b),
                    (a - c).perp_dot(p - c),
                ];
                d.iter().all(|&v| v > 0.0) || d.iter().all(|&v| v < 0.0)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::raster::edge::EdgeTopology;
    use crate::raster::project::Projected;
    use crate::raster::silhouette::SoftSettings;
    use glam::DVec3;

    #[test]
    fn a_square_has_its_perimeter_as_outline_and_normals_point_out() {
        // Two triangles making the square [4, 14]², both wound the same way.
        let uv = [
            DVec2::new(4.0, 4.0),
            DVec2::new(14.0, 4.0),
            DVec2::new(14.0, 14.0),
            DVec2::new(4.0, 14.0),
        ];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let pos: Vec<DVec3> = uv.iter().map(|p| p.extend(0.0)).collect();
        let topo = EdgeTopology::new(&pos, &tris);
        let proj = Projected {
            cam: vec![DVec3::Z; 4],
            uv: uv.to_vec(),
            near: 1e-3,
        };
        let cam = Camera::look_at(DVec3::new(0.0, 0.0, -1.0), DVec3::ZERO, DVec3::Y, 20, 20, 10.0);
        let mut s = EdgeSilhouette::new();
        s.render(&topo, &proj, &tris, &cam, &SoftSettings::default()).unwrap();
        let mut out = Vec::new();
        s.outline_samples(&proj, &tris, 0.5, &mut out);
        let total: f64 = out.iter().map(|o| o.length).sum();
        assert!((total - 40.0).abs() < 1e-9, "{total}");
        let centre = DVec2::splat(9.0);
        for o in &out {
            assert!((o.pos - centre).dot(o.normal) > 4.9, "{o:?}");
            assert!((o.normal.length() - 1.0).abs() < 1e-12);
            let p = uv[o.a as usize] * (1.0 - o.t) + uv[o.b as usize] * o.t;
            assert!((p - o.pos).length() < 1e-12);
        }
        // The diagonal is shared by both faces: not outline.
        assert!(out.iter().all(|o| (o.a, o.b) != (0, 2)));
    }
}
