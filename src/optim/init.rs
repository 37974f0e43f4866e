//! Initialisation (SPEC §4 step 2): the object's centre from the least-squares
//! intersection of the rays through the mask centroids, and an isotropic scale from
//! the masks' areas against the mesh's mean projected area.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::view::View;
use glam::{DMat3, DVec3};

/// The point closest, in the least-squares sense, to the rays through each mask's
/// centroid. With one view (or parallel rays) the depth along the ray is taken from
/// `fallback_depth(view)`.
pub fn triangulate_centre(views: &[View], fallback_depth: impl Fn(&View) -> f64) -> Result<DVec3> {
    let mut rays = Vec::with_capacity(views.len());
    for v in views {
        let c = v.mask().centroid().ok_or_else(|| Error::EmptyMask {
            view: v.name().to_string(),
            file: "mask".into(),
            ignored: false,
        })?;
        rays.push((v.camera().centre(), v.camera().ray_direction(c.x, c.y)));
    }
    if let Some(x) = nearest_point(&rays) {
        return Ok(x);
    }
    // One view or parallel rays: the mean of the points at the fallback depth.
    let mut sum = DVec3::ZERO;
    for (v, (o, d)) in views.iter().zip(rays) {
        let z = fallback_depth(v);
        // Depth is along the optical axis; convert to distance along the ray.
        let axis = v.camera().rotation.transpose() * DVec3::Z;
        sum += o + d * (z / d.dot(axis).max(1e-6));
    }
    Ok(sum / views.len() as f64)
}

/// The point closest, in the least-squares sense, to the rays `(origin, unit
/// direction)`; `None` for fewer than two rays or (nearly) parallel ones.
pub fn nearest_point(rays: &[(DVec3, DVec3)]) -> Option<DVec3> {
    let mut a = DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for &(o, d) in rays {
        let p = DMat3::IDENTITY - DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        a += p;
        b += p * o;
    }
    // Well-conditioned when the rays are not all parallel: the smallest eigenvalue of
    // A is then clearly positive. Test through the determinant relative to its scale.
    let n = rays.len() as f64;
    let x = a.inverse() * b;
    (rays.len() >= 2 && a.determinant() > 1e-6 * n * n * n && x.is_finite()).then_some(x)
}

/// The area of the triangles' surface (model units²).
pub fn surface_area(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// An isotropic scale making the mesh's projected area match the masks' areas at
/// the object's depth in each view: `s² ≈ area_px · z² / (fx·fy · Ā)` with Ā the
/// mesh's mean projected area (a quarter of its surface area for a convex body,
/// Cauchy's formula; a rough but unbiased-enough start for the search, which re-fits it).
pub fn scale_from_areas(views: &[View], centre: DVec3, mean_projected_area: f64) -> f64 {
    let mut acc = 0.0;
    let mut n = 0.0;
    for v in views {
        let (cam, area) = (v.camera(), v.known_area() as f64);
        let z = cam.to_camera(centre).z;
        if z <= 0.0 {
            continue;
        }
        acc += (area * z * z / (cam.fx * cam.fy * mean_projected_area.max(1e-300))).sqrt();
        n += 1.0;
    }
    if n > 0.0 && acc.is_finite() && acc > 0.0 {
        acc / n
    } else {
        1.0
    }
}
