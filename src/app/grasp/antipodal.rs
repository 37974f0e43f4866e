//! Antipodal grasp candidates on a closed triangle mesh (model frame).
//!
//! Input: a [`Mesh`], the gripper's largest opening (model units), how many grasps to
//! return and a seed; output: up to that many [`Grasp`]s. Method (the classic
//! antipodal sampler, e.g. Dex-Net/GPG): draw a surface point p (triangles weighted by
//! area, uniform inside), intersect the line through p along the triangle's normal with
//! every triangle (Möller–Trumbore), keep p only if it is the extreme intersection on
//! its side, take the farthest intersection q on the other side, and accept the pair
//! when q's surface normal lies within the friction cone of the contact line
//! (|n_q · (q − p)/|q − p|| ≥ cos [`ANTIPODAL_CONE_DEG`]) and the opening fits. The
//! test uses |cos|, so a mesh's winding does not matter. Brute force:
//! O(attempts × triangles), fine for ~10⁴ triangles and tens of grasps.

use super::Grasp;
use crate::mesh::Mesh;
use glam::DVec3;
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

/// Half-angle of the friction cone (degrees) an antipodal contact normal must lie within.
pub const ANTIPODAL_CONE_DEG: f64 = 20.0;
/// Clearance added to the contact distance: `width = (1 + clearance) · |q − p|`.
pub const ANTIPODAL_CLEARANCE: f64 = 0.05;
/// Finger depth as a fraction of the mesh's bounding-box diagonal.
pub const ANTIPODAL_DEPTH_FRACTION: f64 = 0.1;
/// Surface points tried per requested grasp before giving up.
const ATTEMPTS_PER_GRASP: usize = 20;

/// Up to `count` antipodal grasps on `mesh` whose opening `width` is at most
/// `max_width` (model units). Each grasp: `centre` midway between the contacts p and
/// q, `closing` from p to q, `width = (1 + `[`ANTIPODAL_CLEARANCE`]`)·|q − p|`,
/// `approach` pointing from outside towards the bounding-box centre, made
/// perpendicular to `closing` (any perpendicular if that vanishes), `depth`
/// = [`ANTIPODAL_DEPTH_FRACTION`] of the bounding-box diagonal, and `score` = |cos| of
/// q's normal against the contact line. At most `20·count` points are tried, so fewer
/// grasps come back on a mesh with few antipodal pairs; none for an empty mesh or a
/// non-positive `max_width`. Deterministic for a seed (`SmallRng`, whose sequence
/// differs between 64-bit and 32-bit targets such as wasm32).
pub fn antipodal_grasps(mesh: &Mesh, max_width: f64, count: usize, seed: u64) -> Vec<Grasp> {
    let mut out = Vec::new();
    let Some(bounds) = mesh.bounds() else {
        return out;
    };
    if max_width.is_nan() || max_width <= 0.0 || count == 0 {
        return out;
    }
    let tris: Vec<[DVec3; 3]> = mesh
        .triangles
        .iter()
        .filter_map(|t| {
            let v = t.map(|i| mesh.positions.get(i as usize).copied());
            Some([v[0]?, v[1]?, v[2]?])
        })
        .collect();
    let normals: Vec<DVec3> = tris.iter().map(|[a, b, c]| (*b - *a).cross(*c - *a)).collect();
    let mut cdf = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for n in &normals {
        total += 0.5 * n.length();
        cdf.push(total);
    }
    let diag = bounds.size().length();
    if total.is_nan() || total <= 0.0 || !diag.is_finite() {
        return out;
    }
    let eps = 1e-7 * diag;
    let cos_cone = ANTIPODAL_CONE_DEG.to_radians().cos();
    let depth = ANTIPODAL_DEPTH_FRACTION * diag;
    let mut rng = SmallRng::seed_from_u64(seed);
    for _ in 0..count.saturating_mul(ATTEMPTS_PER_GRASP) {
        if out.len() == count {
            break;
        }
        let target = rng.gen::<f64>() * total;
        let k = cdf.partition_point(|&c| c <= target).min(tris.len() - 1);
        let (u1, u2): (f64, f64) = (rng.gen(), rng.gen());
        let n_len = normals[k].length();
        if n_len <= 0.0 {
            continue;
        }
        let [a, b, c] = tris[k];
        let r = u1.sqrt();
        let p = a * (1.0 - r) + b * (r * (1.0 - u2)) + c * (r * u2);
        let n = normals[k] / n_len;
        // All crossings of the line p + t·n, apart from p itself.
        let (mut far_pos, mut far_neg) = ((eps, None), (-eps, None));
        for (i, tri) in tris.iter().enumerate() {
            let Some(t) = line_triangle(p, n, tri) else { continue };
            if t > far_pos.0 {
                far_pos = (t, Some(i));
            } else if t < far_neg.0 {
                far_neg = (t, Some(i));
            }
        }
        // p must be the outermost crossing on its side: crossings on one side only.
        let (t, q_tri) = match (far_pos, far_neg) {
            ((t, Some(i)), (_, None)) | ((_, None), (t, Some(i))) => (t, i),
            _ => continue,
        };
        let dir = n * t.signum();
        let dist = t.abs();
        let width = (1.0 + ANTIPODAL_CLEARANCE) * dist;
        if width > max_width {
            continue;
        }
        let nq = normals[q_tri] / normals[q_tri].length();
        let cos_q = nq.dot(dir).abs();
        if cos_q < cos_cone {
            continue;
        }
        let centre = p + 0.5 * dist * dir;
        let inward = bounds.centre() - centre;
        let perp = inward - inward.dot(dir) * dir;
        let approach = if perp.length() > eps {
            perp.normalize()
        } else {
            dir.any_orthonormal_vector()
        };
        out.push(Grasp {
            centre,
            approach,
            closing: dir,
            width,
            depth,
            score: Some(cos_q),
        });
    }
    out
}

/// Möller–Trumbore for a line (t of either sign): the parameter t of the crossing of
/// `o + t·d` with the triangle, or `None` when it misses or runs parallel. Barycentric
/// bounds are relaxed by 1e-9 so a line through a shared edge is not lost.
fn line_triangle(o: DVec3, d: DVec3, [a, b, c]: &[DVec3; 3]) -> Option<f64> {
    const SLACK: f64 = 1e-9;
    let (e1, e2) = (*b - *a, *c - *a);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() <= 1e-12 * e1.length() * e2.length() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - *a;
    let u = s.dot(pv) * inv;
    if !(-SLACK..=1.0 + SLACK).contains(&u) {
        return None;
    }
    let qv = s.cross(e1);
    let v = d.dot(qv) * inv;
    if v < -SLACK || u + v > 1.0 + SLACK {
        return None;
    }
    Some(e2.dot(qv) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_triangle_hits_both_ways() {
        let tri = [
            DVec3::new(-1.0, -1.0, 2.0),
            DVec3::new(1.0, -1.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
        ];
        assert!((line_triangle(DVec3::ZERO, DVec3::Z, &tri).unwrap() - 2.0).abs() < 1e-12);
        assert!((line_triangle(DVec3::ZERO, -DVec3::Z, &tri).unwrap() + 2.0).abs() < 1e-12);
        assert!(line_triangle(DVec3::new(5.0, 0.0, 0.0), DVec3::Z, &tri).is_none());
        assert!(line_triangle(DVec3::ZERO, DVec3::X, &tri).is_none());
    }
}
