//! Hard (binary) silhouettes: which pixel centres a posed mesh covers in a view.
//!
//! Input: a [`Mesh`] under a [`Pose`], or an already [`Projected`] mesh, and the
//! [`Camera`] it was projected with (its width × height is the canvas). Output: a
//! [`Mask`] (one byte per pixel) or a [`BitMask`] (64 pixels per word, for the
//! orientation search's IoU by popcount).
//!
//! The rule: pixel (x, y) is object when its centre, the point (x, y) (SPEC §2), is
//! inside the projection of some triangle's part in front of the near plane. Points
//! exactly on an edge follow the top-left rule of Direct3D/OpenGL, so two triangles
//! sharing an edge never both cover, nor both miss, a centre on it; winding does not
//! matter and zero-area triangles cover nothing. Vertices are snapped to 1/1024 px
//! ([`SUBPIXEL_BITS`]) and every inside test is then exact integer arithmetic
//! (the PyTorch3D-style "centre strictly inside" rule, up to that snapping).
//!
//! Triangles crossing the near plane (`Projected::near`) are clipped against it in
//! camera space (Sutherland–Hodgman) and the polygon is drawn as a fan; triangles
//! wholly behind it are skipped. Polygons reaching past [`GUARD_BAND_PX`] are clipped
//! in the image plane too. Intersection points are computed from the inside vertex
//! of an edge, so neighbours sharing a clipped edge still share it exactly.
//!
//! Cost: each triangle yields one run of pixels per row it spans (see `span.rs`),
//! filled as a byte range or as word masks; nothing is allocated per triangle.

mod bits;
mod span;

pub use bits::BitMask;
pub(crate) use span::snap;
pub use span::{GUARD_BAND_PX, SUBPIXEL_BITS};

use crate::camera::Camera;
use crate::error::Result;
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::project::{check_visible, project_mesh, Projected};
use glam::{DVec2, DVec3};
use span::triangle_spans;

/// The silhouette of `mesh` under `pose` in `camera`, at the camera's full resolution.
pub fn render(mesh: &Mesh, pose: &Pose, camera: &Camera) -> Mask {
    let proj = project_mesh(mesh, pose, camera);
    render_projected(&proj, &mesh.triangles, camera)
}

/// As [`render`], but an [`Error::View`](crate::Error::View) naming `view` when the
/// whole object is behind the camera.
pub fn render_checked(view: &str, mesh: &Mesh, pose: &Pose, camera: &Camera) -> Result<Mask> {
    let proj = project_mesh(mesh, pose, camera);
    check_visible(view, &proj)?;
    Ok(render_projected(&proj, &mesh.triangles, camera))
}

/// The silhouette of already projected triangles; `camera` must be the one `proj`
/// was made with (it sizes the canvas and projects near-plane intersections).
///
/// # Panics
/// If a triangle refers to a vertex beyond `proj` (meshes are validated on load).
pub fn render_projected(proj: &Projected, triangles: &[[u32; 3]], camera: &Camera) -> Mask {
    let mut out = Mask::empty(0, 0);
    render_projected_into(proj, triangles, camera, &mut out);
    out
}

/// As [`render_projected`], writing into `out` (resized and cleared, its allocation reused).
pub fn render_projected_into(proj: &Projected, triangles: &[[u32; 3]], camera: &Camera, out: &mut Mask) {
    render_projected_culled_into(proj, triangles, camera, &[], out);
}

/// As [`render_projected_into`], skipping every triangle `f` with `front[f] ≠ 0`
/// whose projected (snapped) area has the other sign: the back faces of closed,
/// consistently oriented components, whose silhouette their front faces cover alone
/// (`raster::edge::EdgeTopology::front_signs`). Triangles crossing the near plane are
/// always drawn. An empty `front` skips nothing.
pub fn render_projected_culled_into(
    proj: &Projected,
    triangles: &[[u32; 3]],
    camera: &Camera,
    front: &[i8],
    out: &mut Mask,
) {
    let (w, h) = (camera.width, camera.height);
    out.width = w;
    out.height = h;
    out.data.clear();
    out.data.resize(w as usize * h as usize, 0);
    let data = &mut out.data;
    let stride = w as usize;
    for_each_span_culled(proj, triangles, camera, front, &mut |y, x0, x1| {
        data[y * stride + x0..=y * stride + x1].fill(1);
    });
}

/// The silhouette as a bitset (the same pixels as [`render_projected`]), for fast
/// IoU at low resolution: project with a [`Camera::scaled`] copy of the camera.
///
/// # Panics
/// If a triangle refers to a vertex beyond `proj`.
pub fn render_bits(proj: &Projected, triangles: &[[u32; 3]], camera: &Camera) -> BitMask {
    let mut out = BitMask::empty(0, 0);
    render_bits_into(proj, triangles, camera, &mut out);
    out
}

/// As [`render_bits`], writing into `out` (resized and cleared, its allocation reused).
pub fn render_bits_into(proj: &Projected, triangles: &[[u32; 3]], camera: &Camera, out: &mut BitMask) {
    out.reset(camera.width, camera.height);
    for_each_span(proj, triangles, camera, &mut |y, x0, x1| out.fill_span(y, x0, x1));
}

/// A convex polygon: a triangle clipped by up to 5 planes has at most 8 vertices;
/// the spare room absorbs the extra crossings rounding could cause in a sliver.
#[derive(Clone, Copy)]
struct Poly<T> {
    pts: [T; 16],
    n: usize,
}

impl<T: Copy + Default> Poly<T> {
    fn new() -> Self {
        Poly {
            pts: [T::default(); 16],
            n: 0,
        }
    }
    #[inline]
    fn push(&mut self, p: T) {
        if self.n < self.pts.len() {
            self.pts[self.n] = p;
            self.n += 1;
        }
    }
    fn as_slice(&self) -> &[T] {
        &self.pts[..self.n]
    }
}

#[inline]
fn within_guard(p: DVec2) -> bool {
    p.x.abs() <= GUARD_BAND_PX && p.y.abs() <= GUARD_BAND_PX
}

/// Calls `span(y, x0, x1)` for every covered run of every triangle (runs of
/// different triangles may overlap).
fn for_each_span(
    proj: &Projected,
    triangles: &[[u32; 3]],
    camera: &Camera,
    span: &mut impl FnMut(usize, usize, usize),
) {
    for_each_span_culled(proj, triangles, camera, &[], span)
}

/// [`for_each_span`], skipping the culled back faces (see [`render_projected_culled_into`]).
fn for_each_span_culled(
    proj: &Projected,
    triangles: &[[u32; 3]],
    camera: &Camera,
    front: &[i8],
    span: &mut impl FnMut(usize, usize, usize),
) {
    let (w, h) = (camera.width, camera.height);
    if w == 0 || h == 0 {
        return;
    }
    // Each vertex is snapped once; `SLOW` marks those behind the near plane or
    // beyond the guard band, whose triangles take the clipping path.
    const SLOW: i64 = i64::MIN;
    let snapped: Vec<[i64; 2]> = (0..proj.uv.len())
        .map(|i| {
            let p = proj.uv[i];
            if proj.in_front(i) && within_guard(p) {
                [snap(p.x), snap(p.y)]
            } else {
                [SLOW, SLOW]
            }
        })
        .collect();
    for (f, t) in triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| i as usize);
        let v = [snapped[a], snapped[b], snapped[c]];
        if v[0][0] != SLOW && v[1][0] != SLOW && v[2][0] != SLOW {
            if let Some(&keep) = front.get(f) {
                if keep != 0 {
                    let area = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
                    if area.signum() as i8 != keep {
                        continue;
                    }
                }
            }
            triangle_spans(v, w, h, span);
            continue;
        }
        let front = [proj.in_front(a), proj.in_front(b), proj.in_front(c)];
        let mut poly = Poly::<DVec2>::new();
        if front == [true; 3] {
            for i in [a, b, c] {
                poly.push(proj.uv[i]);
            }
        } else if front == [false; 3] {
            continue;
        } else {
            // Sutherland–Hodgman against z ≥ near, in camera space.
            let idx = [a, b, c];
            for k in 0..3 {
                let (i, j) = (idx[k], idx[(k + 1) % 3]);
                let (fi, fj) = (front[k], front[(k + 1) % 3]);
                if fi {
                    poly.push(proj.uv[i]);
                }
                if fi != fj {
                    let (inside, outside) = if fi { (i, j) } else { (j, i) };
                    let p = near_intersection(proj.cam[inside], proj.cam[outside], proj.near);
                    poly.push(camera.project(p));
                }
            }
        }
        if poly.as_slice().iter().any(|p| !p.is_finite()) {
            continue;
        }
        if !poly.as_slice().iter().all(|&p| within_guard(p)) {
            poly = clip_to_guard_band(&poly);
        }
        fan(poly.as_slice(), w, h, span);
    }
}

/// The point where the segment from `inside` (z ≥ near) to `outside` (z < near) meets z = near.
#[inline]
fn near_intersection(inside: DVec3, outside: DVec3, near: f64) -> DVec3 {
    let t = (inside.z - near) / (inside.z - outside.z);
    let mut p = inside + (outside - inside) * t;
    p.z = near;
    p
}

/// Clips a convex polygon to |x| ≤ G, |y| ≤ G (G = [`GUARD_BAND_PX`]).
fn clip_to_guard_band(poly: &Poly<DVec2>) -> Poly<DVec2> {
    let mut cur = *poly;
    // (axis, sign): keep points with sign · p[axis] ≤ G.
    for (axis, sign) in [(0usize, 1.0f64), (0, -1.0), (1, 1.0), (1, -1.0)] {
        let pts = cur.as_slice();
        let mut next = Poly::<DVec2>::new();
        let dist = |p: DVec2| GUARD_BAND_PX - sign * p[axis];
        for k in 0..pts.len() {
            let (p, q) = (pts[k], pts[(k + 1) % pts.len()]);
            let (dp, dq) = (dist(p), dist(q));
            if dp >= 0.0 {
                next.push(p);
            }
            if (dp >= 0.0) != (dq >= 0.0) {
                let (i, o, di, d_o) = if dp >= 0.0 { (p, q, dp, dq) } else { (q, p, dq, dp) };
                let mut x = i + (o - i) * (di / (di - d_o));
                x[axis] = sign * GUARD_BAND_PX;
                next.push(x);
            }
        }
        cur = next;
        if cur.n < 3 {
            break;
        }
    }
    cur
}

/// Draws a convex polygon as the fan (p0, pk, pk+1).
fn fan(pts: &[DVec2], w: u32, h: u32, span: &mut impl FnMut(usize, usize, usize)) {
    if pts.len() < 3 {
        return;
    }
    let s = |p: DVec2| [snap(p.x), snap(p.y)];
    let p0 = s(pts[0]);
    let mut prev = s(pts[1]);
    for &p in &pts[2..] {
        let cur = s(p);
        triangle_spans([p0, prev, cur], w, h, span);
        prev = cur;
    }
}
