//! The uncertainty of a finished fit: every view's information at the fitted pose,
//! against its mask on its object window at the window's own pixels (at most 512 on
//! the long side), combined with the fit's robust weights into the covariance and
//! its standard deviations (module doc of `crate::uncertainty`).

use super::{combine, sandwich, std_dev, view_information, NoiseModel, Uncertainty};
use crate::error::Result;
use crate::loss::target::ViewTarget;
use crate::optim::params::ScaleMode;
use crate::pose::Pose;
use crate::raster::silhouette::RenderMesh;
use crate::view::View;
use crate::window::Window;

/// The long side of the canvas the information is measured on, at most.
pub const RESOLUTION: u32 = 512;

/// The uncertainty of `pose` fitted to `views` (seen through `windows`, with the
/// fit's per-view `weights`; a view of weight 0 adds nothing), over the parameters
/// `mode`.
///
/// Errors: no view has an outline to measure (e.g. the object is outside every
/// window), or the information is not finite.
pub fn fit_uncertainty(
    model: &RenderMesh,
    views: &[View],
    windows: &[Window],
    pose: &Pose,
    weights: &[f64],
    mode: ScaleMode,
    noise: &NoiseModel,
) -> Result<Uncertainty> {
    let mut infos = Vec::with_capacity(views.len());
    let mut used = Vec::with_capacity(views.len());
    for ((view, window), &w) in views.iter().zip(windows).zip(weights) {
        if w <= 0.0 {
            continue;
        }
        let target = ViewTarget::new(view, *window, RESOLUTION, true)?;
        infos.push(view_information(model, pose, &target, noise)?);
        used.push(w);
    }
    let (h, b, noise_power) = combine(&infos, &used, noise)?;
    let cov = sandwich(&h, &b, mode, noise)?;
    let (sq, len) = infos.iter().zip(&used).fold((0.0, 0.0), |(s, l), (i, &w)| {
        (s + w * i.residual_sq, l + w * i.outline_px)
    });
    let rms = if len > 0.0 { (sq / len).sqrt() } else { 0.0 };
    Ok(Uncertainty {
        std_dev: std_dev(&model.mesh, pose, &cov, rms),
        covariance: cov,
        information: h,
        noise: b,
        noise_power,
        mode,
    })
}
