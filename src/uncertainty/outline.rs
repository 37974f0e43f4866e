//! One view's information about the pose, from the outline of the model rendered at
//! the pose (`raster::edge` outline samples): at each sample s, the outline's normal
//! velocity `g = n̂ᵀ ∂q/∂θ` (q the sample, interpolated between its edge's ends) and,
//! against a mask, the residual `n` = the mask contour's signed distance at q
//! (positive where the mask reaches beyond the model). From them `H = ∮ g gᵀ ds`, the
//! residual's variance and its correlation length along the outline (module doc of
//! `crate::uncertainty`).

use super::{Mat9, NoiseModel, Vec9, DIM};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::loss::contour::ContourTarget;
use crate::loss::target::ViewTarget;
use crate::pose::Pose;
use crate::raster::edge::{EdgeSilhouette, OutlineSample};
use crate::raster::project::PoseProjection;
use crate::raster::silhouette::RenderMesh;
use crate::raster::silhouette::SoftSettings;
use glam::DVec2;

/// What one view tells about the pose.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewInformation {
    /// `∮ g gᵀ ds` over the outline (px of outline × (px per unit θ)²).
    pub h: Mat9,
    /// Outline length used, canvas pixels.
    pub outline_px: f64,
    /// `∮ n² ds` (zero without a mask), px³.
    pub residual_sq: f64,
    /// λ, the residual's integral correlation length along the outline, pixels
    /// ([`correlation_length`]; zero without a mask).
    pub correlation_px: f64,
    /// `∮ g n ds`: `H⁻¹` of it is the least-squares step towards the mask.
    pub score: Vec9,
}

impl ViewInformation {
    /// The residual's variance per unit length times its correlation length,
    /// `σ²λ` (px³): the boundary noise's power, so that `∮∮ g ν ν' g'ᵀ ≈ σ²λ·H`.
    pub fn noise_power(&self) -> f64 {
        if self.outline_px > 0.0 {
            self.residual_sq / self.outline_px * self.correlation_px
        } else {
            0.0
        }
    }

    /// RMS residual along the outline, pixels.
    pub fn rms_px(&self) -> f64 {
        if self.outline_px > 0.0 {
            (self.residual_sq / self.outline_px).sqrt()
        } else {
            0.0
        }
    }
}

/// Renders the outline of `model` at `pose` in `camera` (a canvas camera).
fn outline(
    model: &RenderMesh,
    pose: &Pose,
    camera: &Camera,
    noise: &NoiseModel,
) -> Result<(PoseProjection, Vec<OutlineSample>)> {
    let mut pp = PoseProjection::default();
    pp.project(&model.mesh, pose, camera);
    let mut sil = EdgeSilhouette::new();
    let soft = SoftSettings { sigma: 0.02, eps: 1e-4 };
    sil.render(model.topology(), &pp.proj, &model.mesh.triangles, camera, &soft)?;
    let mut samples = Vec::new();
    sil.outline_samples(&pp.proj, &model.mesh.triangles, noise.spacing_px, &mut samples);
    Ok((pp, samples))
}

/// `g` of a sample: its outward normal velocity per unit θ.
fn velocity(pp: &PoseProjection, s: &OutlineSample) -> Vec9 {
    let ja = pp.vertex_pose_jacobian(s.a as usize);
    let jb = pp.vertex_pose_jacobian(s.b as usize);
    let lanes = |j: &[[wide::f64x2; 5]; 2], r: usize| -> [f64; 10] {
        let mut out = [0.0; 10];
        for (c, l) in j[r].iter().enumerate() {
            let v = l.to_array();
            out[2 * c] = v[0];
            out[2 * c + 1] = v[1];
        }
        out
    };
    let (au, av, bu, bv) = (lanes(&ja, 0), lanes(&ja, 1), lanes(&jb, 0), lanes(&jb, 1));
    let (n, t) = (s.normal, s.t);
    Vec9::from_fn(|k, _| (1.0 - t) * (n.x * au[k] + n.y * av[k]) + t * (n.x * bu[k] + n.y * bv[k]))
}

/// The signed distance of the mask contour at `q` (bilinear between pixel centres;
/// positive outside the mask), or `None` where a pixel it needs is unknown or off the
/// canvas.
fn signed_distance(contour: &ContourTarget, target: &ViewTarget, q: DVec2) -> Option<f64> {
    let (w, h) = (contour.width as i64, contour.height as i64);
    let (x0, y0) = (q.x.floor() as i64, q.y.floor() as i64);
    let (fx, fy) = (q.x - x0 as f64, q.y - y0 as f64);
    let mut acc = 0.0;
    for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
        for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
            let (x, y) = (x0 + dx, y0 + dy);
            if !((0..w).contains(&x) && (0..h).contains(&y)) {
                return None;
            }
            let i = (y * w + x) as usize;
            if !target.is_known(i) {
                return None;
            }
            acc += wx * wy * contour.signed_distance(i);
        }
    }
    Some(acc)
}

/// The integral correlation length λ of residuals along the outline,
/// `λ = Σ_i r_i Σ_{j: |q_i − q_j| < D} K(|q_i − q_j|/D) r_j / Σ_i n_i² Δs_i` (r = n Δs;
/// K the Bartlett kernel 1 − d/D, so that a white residual gives about its sample
/// spacing and an exponentially correlated one of length ℓ about 2ℓ), at least ½ px.
/// `residuals` are (position, n·Δs); `sum_sq` is Σ n² Δs. Samples are binned into cells
/// of D so that the pairs cost O(N·neighbours).
pub fn correlation_length(residuals: &[(DVec2, f64)], sum_sq: f64, bandwidth: f64) -> f64 {
    if residuals.is_empty() || sum_sq.is_nan() || sum_sq <= 0.0 {
        return 0.0;
    }
    let d = bandwidth.max(1.0);
    let key = |p: DVec2| ((p.x / d).floor() as i64, (p.y / d).floor() as i64);
    let mut cells: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (i, (p, _)) in residuals.iter().enumerate() {
        cells.entry(key(*p)).or_default().push(i);
    }
    let mut acc = 0.0;
    for (p, r) in residuals {
        let (cx, cy) = key(*p);
        let mut near = 0.0;
        for dy in -1..=1 {
            for dx in -1..=1 {
                for &j in cells.get(&(cx + dx, cy + dy)).map(Vec::as_slice).unwrap_or(&[]) {
                    let (q, rj) = residuals[j];
                    let dist = p.distance(q);
                    if dist < d {
                        near += (1.0 - dist / d) * rj;
                    }
                }
            }
        }
        acc += r * near;
    }
    (acc / sum_sq).max(0.5)
}

/// The information of one view about `pose` against its target (module doc), at the
/// target's canvas.
///
/// Errors: the target's mask is empty at its resolution, or the render fails.
pub fn view_information(
    model: &RenderMesh,
    pose: &Pose,
    target: &ViewTarget,
    noise: &NoiseModel,
) -> Result<ViewInformation> {
    let built;
    let contour = match &target.contour {
        Some(c) => c,
        None => {
            let (w, h) = target.size();
            built = ContourTarget::from_parts(
                w,
                h,
                &target.mask,
                target.known.as_deref(),
                target.contour_cap,
                &target.name,
            )?;
            &built
        }
    };
    let (pp, samples) = outline(model, pose, &target.camera, noise)?;
    let mut info = ViewInformation {
        h: Mat9::zeros(),
        outline_px: 0.0,
        residual_sq: 0.0,
        correlation_px: 0.0,
        score: Vec9::zeros(),
    };
    // The residual at each sample, for the correlation length.
    let mut residuals: Vec<(DVec2, f64)> = Vec::with_capacity(samples.len());
    for s in &samples {
        let Some(sd) = signed_distance(contour, target, s.pos) else {
            continue;
        };
        let n = -sd;
        let g = velocity(&pp, s);
        info.h += g * g.transpose() * s.length;
        info.outline_px += s.length;
        info.residual_sq += n * n * s.length;
        info.score += g * (n * s.length);
        residuals.push((s.pos, n * s.length));
    }
    info.correlation_px = correlation_length(&residuals, info.residual_sq, noise.bandwidth_px);
    if !info.h.iter().all(|v| v.is_finite()) {
        return Err(Error::View {
            view: target.name.clone(),
            problem: "the outline's information is not finite".into(),
        });
    }
    Ok(info)
}

/// `H = ∮ g gᵀ ds` of the outline of `model` at `pose` seen by `camera` (a canvas
/// camera): what a photograph from there would tell, before it is taken.
///
/// Errors: the render fails (e.g. an oversized canvas).
pub fn outline_information(
    model: &RenderMesh,
    pose: &Pose,
    camera: &Camera,
    noise: &NoiseModel,
) -> Result<(Mat9, f64)> {
    let (pp, samples) = outline(model, pose, camera, noise)?;
    let mut h = Mat9::zeros();
    let mut length = 0.0;
    for s in &samples {
        let g = velocity(&pp, s);
        h += g * g.transpose() * s.length;
        length += s.length;
    }
    debug_assert_eq!(h.nrows(), DIM);
    Ok((h, length))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3;
    use crate::view::View;
    use crate::window::Window;
    use glam::DVec3;

    fn scene() -> (RenderMesh, Pose, Camera) {
        let mesh = crate::app::synth::blob_mesh(12, 16);
        let pose = Pose {
            rotation: so3::exp(DVec3::new(0.3, -0.4, 0.2)),
            translation: DVec3::new(0.05, -0.02, 0.0),
            scale: DVec3::new(1.0, 0.7, 0.85),
        };
        let cam = Camera::look_at(DVec3::new(0.4, -0.3, -4.0), DVec3::ZERO, DVec3::Y, 96, 80, 90.0);
        (RenderMesh::new(mesh), pose, cam)
    }

    #[test]
    fn outline_velocity_matches_the_area_change_of_the_hard_silhouette() {
        // ∮ g ds is the derivative of the silhouette's area: check against central
        // differences of the hard coverage's pixel count (large moves so that the
        // pixel count resolves them).
        let (model, pose, cam) = scene();
        let noise = NoiseModel::default();
        let (pp, samples) = outline(&model, &pose, &cam, &noise).unwrap();
        let mut darea = Vec9::zeros();
        for s in &samples {
            darea += velocity(&pp, s) * s.length;
        }
        // Supersampled 8× so that the pixel count resolves the area to ~0.05 px².
        let fine = cam.scaled(cam.width * 8, cam.height * 8);
        let area = |p: &Pose| {
            let m = crate::raster::hard::render(&model.mesh, p, &fine);
            m.data.iter().filter(|&&v| v != 0).count() as f64 / 64.0
        };
        let scale = darea.abs().max();
        for k in 0..DIM {
            let h = 0.03;
            let mut d = Vec9::zeros();
            d[k] = h;
            let fd = (area(&pose.perturbed(&d)) - area(&pose.perturbed(&(-d)))) / (2.0 * h);
            assert!(
                (fd - darea[k]).abs() < 0.04 * scale,
                "θ{k}: outline {} vs hard differences {fd}",
                darea[k]
            );
        }
    }

    #[test]
    fn a_mask_of_the_pose_itself_gives_sub_pixel_residuals_and_a_moved_one_more() {
        let (model, pose, cam) = scene();
        let noise = NoiseModel::default();
        let info_at = |truth: &Pose| {
            let mask = crate::raster::hard::render(&model.mesh, truth, &cam);
            let view = View::new("v", cam, mask, None, None, &Default::default()).unwrap();
            let target = ViewTarget::new(&view, Window::full(&cam), 96, true).unwrap();
            view_information(&model, &pose, &target, &noise).unwrap()
        };
        let same = info_at(&pose);
        assert!(same.rms_px() < 0.45, "{}", same.rms_px());
        assert!(same.outline_px > 100.0);
        let moved = Pose {
            translation: pose.translation + DVec3::new(0.05, 0.0, 0.0),
            ..pose
        };
        let off = info_at(&moved);
        assert!(
            off.rms_px() > 2.0 * same.rms_px(),
            "{} vs {}",
            off.rms_px(),
            same.rms_px()
        );
        // The least-squares step from the residuals moves the outline onto the mask.
        let hi = (off.h + Mat9::identity() * (1e-9 * off.h.trace()))
            .try_inverse()
            .unwrap();
        let stepped = pose.perturbed(&(hi * off.score));
        let mask = crate::raster::hard::render(&model.mesh, &moved, &cam);
        let view = View::new("v", cam, mask, None, None, &Default::default()).unwrap();
        let target = ViewTarget::new(&view, Window::full(&cam), 96, true).unwrap();
        let after = view_information(&model, &stepped, &target, &noise).unwrap();
        assert!(
            after.rms_px() < 0.5 * off.rms_px(),
            "{} after vs {} before",
            after.rms_px(),
            off.rms_px()
        );
    }
}
