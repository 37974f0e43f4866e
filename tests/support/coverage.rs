//! Is the reported uncertainty calibrated? Fits synthetic scenes with known truth
//! (2–4 views, clean or roughened masks) from no initial pose and measures, for each,
//! the squared Mahalanobis distance of the true error under the reported covariance
//! and the true ADD against the reported 95 % ADD bound; and the next-best-view and
//! camera-correction checks' scenes. Used by the second tier's statistical tests
//! (`tests/tier2`), the calibration of κ (`localisebot::uncertainty::NoiseModel::inflation`).

use localisebot::app::synth::{roughen, synthesize, SynthSettings};
use localisebot::metrics;
use localisebot::uncertainty::{mahalanobis_sq, pose_error, Viewpoints, CHI2_9_95};
use localisebot::{Error, Result};
use localisebot::{Estimator, FitSettings, Mat9, Mesh, Verdict, View};

/// How the scenes are made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoverageScenes {
    /// Image width and height, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Boundary noise σ of the masks, pixels (0: clean hard renders).
    pub noise_px: f64,
    /// Correlation length of the boundary noise, pixels.
    pub correlation_px: f64,
}

/// One scene's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct CoverageCase {
    /// The scene's seed.
    pub seed: u64,
    /// Its number of views.
    pub views: usize,
    /// Whether the fit was `ambiguous` (its region then the union of its poses').
    pub ambiguous: bool,
    /// `eᵀΣ⁻¹e` of the true error e under the reported Σ (for an ambiguous fit, the
    /// smallest over its pose and its alternatives, each under its own Σ).
    pub mahalanobis_sq: f64,
    /// The true ADD, scene units.
    pub add: f64,
    /// The reported 95 % ADD bound, scene units.
    pub add_95: f64,
    /// The true rotation error, degrees.
    pub rotation_deg: f64,
    /// The reported rotation standard deviations' norm, degrees.
    pub rotation_sd_deg: f64,
}

impl CoverageCase {
    /// Whether the truth lies inside the 95 % ellipsoid.
    pub fn inside(&self) -> bool {
        self.mahalanobis_sq <= CHI2_9_95
    }

    /// Whether the true ADD is within the reported 95 % bound.
    pub fn add_inside(&self) -> bool {
        self.add <= self.add_95
    }
}

/// Fits the scene of `seed` (2 + seed mod 3 views) and measures it; `None` when the fit's
/// verdict is `failed` (it then reports no pose to be sure of).
///
/// Errors: the scene cannot be made, or the fit reports no uncertainty.
pub fn coverage_case(mesh: &Mesh, seed: u64, scenes: &CoverageScenes) -> Result<Option<CoverageCase>> {
    let views = 2 + (seed % 3) as usize;
    let settings = SynthSettings {
        views,
        width: scenes.width,
        height: scenes.height,
        seed,
        ..Default::default()
    };
    let scene = synthesize(mesh, &settings, None)?;
    let views_v: Vec<View> = scene
        .views()
        .into_iter()
        .enumerate()
        .map(|(i, v)| {
            let mask = roughen(v.mask(), scenes.noise_px, scenes.correlation_px, seed * 64 + i as u64);
            View::new(v.name(), *v.camera(), mask, None, None, &Default::default())
        })
        .collect::<Result<_>>()?;
    let mut est = Estimator::new(mesh.clone(), views_v, None, FitSettings::default())?;
    est.run(1_000_000)?;
    if est.judgement().map(|j| j.verdict) == Some(Verdict::Failed) {
        return Ok(None);
    }
    let pose = est.pose();
    let u = match est.uncertainty() {
        Some(Ok(u)) => u.clone(),
        Some(Err(e)) => return Err(Error::Settings(format!("scene {seed}: no uncertainty: {e}"))),
        None => return Err(Error::Settings(format!("scene {seed}: the fit did not end"))),
    };
    let e = pose_error(&pose, &scene.pose);
    let cov: &Mat9 = &u.covariance;
    let sd = u.std_dev.rotation_deg;
    let mode = est.settings().scale_mode;
    // An ambiguous fit's 95 % region is a mixture's: the union of its poses' ellipsoids.
    let mut m2 = mahalanobis_sq(cov, &e, mode)?;
    for a in est.alternatives() {
        if let Ok(ua) = &a.uncertainty {
            m2 = m2.min(mahalanobis_sq(&ua.covariance, &pose_error(&a.pose, &scene.pose), mode)?);
        }
    }
    Ok(Some(CoverageCase {
        seed,
        views,
        ambiguous: !est.alternatives().is_empty(),
        mahalanobis_sq: m2,
        add: metrics::add(mesh, &pose, &scene.pose),
        add_95: u.std_dev.add_95,
        rotation_deg: metrics::rotation_error_deg(&pose, &scene.pose),
        rotation_sd_deg: (sd[0] * sd[0] + sd[1] * sd[1] + sd[2] * sd[2]).sqrt(),
    }))
}

/// The fraction of `cases` inside the 95 % ellipsoid and within the ADD bound.
pub fn coverage(cases: &[CoverageCase]) -> (f64, f64) {
    let n = cases.len().max(1) as f64;
    (
        cases.iter().filter(|c| c.inside()).count() as f64 / n,
        cases.iter().filter(|c| c.add_inside()).count() as f64 / n,
    )
}

/// One scene of the next-best-view check.
#[derive(Debug, Clone, PartialEq)]
pub struct NextViewCase {
    /// The scene's seed.
    pub seed: u64,
    /// The true ADD of the 2-view fit.
    pub add_before: f64,
    /// The true ADD after adding the top-ranked candidate and refitting: the geometric
    /// mean over `draws` noise draws of the new view's mask (see [`next_view_case`]).
    pub add_top: f64,
    /// The same for each random candidate instead.
    pub add_random: Vec<f64>,
    /// The noise draws each candidate's ADD is averaged over.
    pub draws: u64,
    /// The top candidate's ADD under each draw.
    pub top_draws: Vec<f64>,
    /// Each random candidate's ADD under each draw.
    pub random_draws: Vec<Vec<f64>>,
}

impl NextViewCase {
    /// The median of the random candidates' ADDs.
    pub fn median_random(&self) -> f64 {
        metrics::median(&self.add_random)
    }

    /// Whether the top candidate beat the median random one (expected ADDs).
    pub fn top_wins(&self) -> bool {
        self.add_top < self.median_random()
    }

    /// Whether it did on noise draw `draw` alone: the outcome of single photographs.
    pub fn top_wins_draw(&self, draw: usize) -> bool {
        let random: Vec<f64> = self.random_draws.iter().filter_map(|r| r.get(draw).copied()).collect();
        self.top_draws.get(draw).is_some_and(|&t| t < metrics::median(&random))
    }
}

/// The next-best-view check on the scene of `seed`: a 2-view fit (masks as
/// `scenes`; the synthetic scene's two cameras, or with `spread_deg` two cameras that
/// far apart about the object), `candidates` viewpoints over `shell` ranked, then the fit refined from its pose
/// with a third view from the top candidate, and again with each of `randoms` other
/// candidates drawn at random (masks rendered at the truth, roughened alike; a random
/// candidate that does not see the truth whole is left out). Each candidate's ADD is
/// the geometric mean over `draws` (≥ 1) independent noise draws of its mask, each
/// refitted: the expected outcome of a photograph from there, which is what a ranking
/// can predict — a single draw's ADD varies between draws three times as much as the
/// expected ADD between candidates (docs/benchmark-history.md "Next best view"). `None` when the
/// 2-view fit fails or is more than 10 % of the diameter off, or the top candidate
/// does not see the truth whole.
///
/// Errors: the scene cannot be made or a fit errs.
#[allow(clippy::too_many_arguments)]
pub fn next_view_case(
    mesh: &Mesh,
    seed: u64,
    scenes: &CoverageScenes,
    candidates: usize,
    shell: Viewpoints,
    randoms: usize,
    draws: u64,
    spread_deg: Option<f64>,
) -> Result<Option<NextViewCase>> {
    use rand::seq::SliceRandom;
    use rand::SeedableRng;
    let Some(setup) = NextViewSetup::new(mesh, seed, scenes, candidates, shell, spread_deg)? else {
        return Ok(None);
    };
    let Some((&top, rest)) = setup.ranked.split_first() else {
        return Err(Error::Settings(format!("scene {seed}: no candidate sees the object")));
    };
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed ^ 0x6e62_7620);
    let picks: Vec<usize> = rest.choose_multiple(&mut rng, randoms).copied().collect();
    let draws = draws.max(1);
    let Some(top_draws) = setup.refits(top, draws)? else {
        return Ok(None);
    };
    let random_draws = picks
        .iter()
        .filter_map(|&i| setup.refits(i, draws).transpose())
        .collect::<Result<Vec<Vec<f64>>>>()?;
    Ok(Some(NextViewCase {
        seed,
        add_before: setup.add_before(),
        add_top: metrics::geometric_mean(&top_draws),
        add_random: random_draws.iter().map(|r| metrics::geometric_mean(r)).collect(),
        draws,
        top_draws,
        random_draws,
    }))
}

/// The 2-view fit of the next-best-view check (see [`next_view_case`]) and its ranked
/// candidates, ready to be refitted with a third view from any of them.
#[derive(Debug, Clone)]
pub struct NextViewSetup {
    mesh: Mesh,
    seed: u64,
    scenes: CoverageScenes,
    truth: localisebot::Pose,
    views: Vec<View>,
    /// The 2-view fit's pose.
    pub fitted: localisebot::Pose,
    /// The candidate cameras, in the sphere's order.
    pub cameras: Vec<localisebot::Camera>,
    /// The indices of the candidates that see the object whole, best first.
    pub ranked: Vec<usize>,
}

impl NextViewSetup {
    /// Makes the scene of `seed` and fits its two views (see [`next_view_case`]);
    /// `None` when that fit fails or is more than 10 % of the diameter off.
    ///
    /// Errors: the scene cannot be made or the fit errs.
    pub fn new(
        mesh: &Mesh,
        seed: u64,
        scenes: &CoverageScenes,
        candidates: usize,
        shell: Viewpoints,
        spread_deg: Option<f64>,
    ) -> Result<Option<NextViewSetup>> {
        use localisebot::uncertainty::candidate_viewpoints;
        let settings = SynthSettings {
            views: 2,
            width: scenes.width,
            height: scenes.height,
            seed,
            ..Default::default()
        };
        let mut scene = synthesize(mesh, &settings, None)?;
        if let Some(spread) = spread_deg {
            // Two stops of an arm on one side of the object: view 1 is view 0 turned by
            // `spread` about view 0's image-up through the object's centre.
            let c0 = scene.cameras[0];
            let centre = mesh
                .bounds()
                .map_or(scene.pose.translation, |b| scene.pose.apply(b.centre()));
            let up = -(c0.rotation.transpose() * glam::DVec3::Y);
            let eye = centre + glam::DQuat::from_axis_angle(up, spread.to_radians()) * (c0.centre() - centre);
            let mut c1 = localisebot::Camera::look_at(eye, centre, up, c0.width, c0.height, c0.fx);
            c1.cx = c0.cx;
            c1.cy = c0.cy;
            scene.cameras[1] = c1;
        }
        let mut setup = NextViewSetup {
            mesh: mesh.clone(),
            seed,
            scenes: *scenes,
            truth: scene.pose,
            views: Vec::new(),
            fitted: scene.pose,
            cameras: Vec::new(),
            ranked: Vec::new(),
        };
        setup.views = scene
            .cameras
            .iter()
            .enumerate()
            .map(|(i, c)| setup.view(&format!("view{i}"), *c, i as u64))
            .collect::<Result<_>>()?;
        let mut est = Estimator::new(mesh.clone(), setup.views.clone(), None, FitSettings::default())?;
        est.run(1_000_000)?;
        if est.judgement().map(|j| j.verdict) == Some(Verdict::Failed) {
            return Ok(None);
        }
        setup.fitted = est.pose();
        // A 2-view fit that did not find the object (ADD above the usual 10 % of the
        // diameter) has no uncertainty worth planning with: not counted.
        if metrics::pose_errors(mesh, &setup.fitted, &setup.truth).add_rel > 0.1 {
            return Ok(None);
        }
        let model = localisebot::raster::silhouette::RenderMesh::new(mesh.clone());
        setup.cameras = candidate_viewpoints(&model, &setup.views, &setup.fitted, candidates, shell)?;
        setup.ranked = est
            .suggest_views(Some(&setup.cameras), shell)?
            .iter()
            .filter(|r| r.predicted_add_rms.is_finite())
            .map(|r| r.index)
            .collect();
        Ok(Some(setup))
    }

    /// The true ADD of the 2-view fit.
    pub fn add_before(&self) -> f64 {
        metrics::add(&self.mesh, &self.fitted, &self.truth)
    }

    /// [`NextViewSetup::refit`]'s ADD under each of draws `0..draws`; `None` when
    /// the candidate does not see the truth.
    ///
    /// Errors: a fit errs.
    pub fn refits(&self, index: usize, draws: u64) -> Result<Option<Vec<f64>>> {
        (0..draws).map(|d| self.refit(index, d)).collect()
    }

    /// The true ADD after refitting from the 2-view pose with a third view from
    /// candidate `index`, its mask roughened with noise draw `draw` ([`next_view_case`]
    /// uses draws `0..draws`); `None` when the candidate does not see the truth.
    ///
    /// Errors: the fit errs.
    pub fn refit(&self, index: usize, draw: u64) -> Result<Option<f64>> {
        let mut v = self.views.clone();
        // The candidate may not see the truth whole (it was placed around the fit).
        let Ok(extra) = self.view("next", self.cameras[index], 32 + index as u64 + 1000 * draw) else {
            return Ok(None);
        };
        v.push(extra);
        let mut e = Estimator::new(self.mesh.clone(), v, Some(self.fitted), FitSettings::default())?;
        e.run(1_000_000)?;
        Ok(Some(metrics::add(&self.mesh, &e.pose(), &self.truth)))
    }

    fn view(&self, name: &str, cam: localisebot::Camera, salt: u64) -> Result<View> {
        let mask = localisebot::raster::hard::render(&self.mesh, &self.truth, &cam);
        let mask = roughen(
            &mask,
            self.scenes.noise_px,
            self.scenes.correlation_px,
            self.seed * 64 + salt,
        );
        View::new(name, cam, mask, None, None, &Default::default())
    }
}

/// The errors of one fit of the camera-correction check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraCase {
    /// Rotation error, degrees.
    pub rotation_deg: f64,
    /// Scale error: the largest per-axis |ŝ/s − 1|.
    pub scale: f64,
    /// ADD relative to the diameter.
    pub add_rel: f64,
    /// With `refine_cameras`: whether the corrections were applied.
    pub applied: Option<bool>,
}

/// The camera-correction check on the scene of `seed` (3 + seed mod 2 views, masks
/// rendered with the true cameras): the fit is given cameras each rotated by
/// `rotation_deg` about a random axis and moved by `distance` of its distance to the
/// object in a random direction (0 and 0: the true cameras), with or without
/// `refine_cameras` (the default prior). `None` when the fit fails.
///
/// Errors: the scene cannot be made or the fit errs.
pub fn camera_case(
    mesh: &Mesh,
    seed: u64,
    scenes: &CoverageScenes,
    rotation_deg: f64,
    distance: f64,
    refine: bool,
) -> Result<Option<CameraCase>> {
    use rand::{Rng, SeedableRng};
    let settings = SynthSettings {
        views: 3 + (seed % 2) as usize,
        width: scenes.width,
        height: scenes.height,
        seed,
        ..Default::default()
    };
    let scene = synthesize(mesh, &settings, None)?;
    let centre = mesh
        .bounds()
        .map_or(scene.pose.translation, |b| scene.pose.apply(b.centre()));
    let mut rng = rand::rngs::SmallRng::seed_from_u64(seed ^ 0x0ca3_e7a5);
    let unit = |rng: &mut rand::rngs::SmallRng| loop {
        let v = glam::DVec3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        if (0.1..=1.0).contains(&v.length()) {
            return v.normalize();
        }
    };
    let views: Vec<View> = scene
        .views()
        .into_iter()
        .enumerate()
        .map(|(i, v)| {
            let cam = *v.camera();
            let r = localisebot::so3::exp(unit(&mut rng) * rotation_deg.to_radians());
            let shift = unit(&mut rng) * distance * cam.centre().distance(centre);
            let mask = roughen(v.mask(), scenes.noise_px, scenes.correlation_px, seed * 64 + i as u64);
            let off = localisebot::Camera {
                rotation: r * cam.rotation,
                translation: r * cam.translation + shift,
                ..cam
            };
            View::new(v.name(), off, mask, None, None, &Default::default())
        })
        .collect::<Result<_>>()?;
    let mut fit = FitSettings::default();
    if refine {
        fit.refine_cameras = Some(localisebot::CameraPrior::default());
    }
    let mut est = Estimator::new(mesh.clone(), views, None, fit)?;
    est.run(1_000_000)?;
    if est.judgement().map(|j| j.verdict) == Some(Verdict::Failed) {
        return Ok(None);
    }
    if let Some(Err(e)) = est.camera_corrections() {
        return Err(Error::Settings(format!("scene {seed}: cameras not corrected: {e}")));
    }
    let e = metrics::pose_errors(mesh, &est.pose(), &scene.pose);
    Ok(Some(CameraCase {
        rotation_deg: e.rotation_deg,
        scale: e.scale,
        add_rel: e.add_rel,
        applied: est.camera_test().map(|t| t.applied),
    }))
}
