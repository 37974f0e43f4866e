//! [`FitSetup`]: what a fit is built from, made once — the mesh ready to render (with
//! its levels of detail) and its clustered copy for the search, the views and their
//! object windows, the settings, the mesh's centre and radius, and the search's
//! rotations. The estimator and every [`Shard`](super::Shard) (another thread, a Web
//! Worker) hold the same setup, so whoever computes a step computes it alike.

use super::settings::FitSettings;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::silhouette::RenderMesh;
use crate::uncertainty::{
    candidate_viewpoints, fit_uncertainty, next_view, rank_views, NoiseModel, RankedView, Viewpoints,
};
use crate::view::View;
use crate::window::Window;
use crate::{metrics, symmetry};
use glam::{DMat3, DVec3};
use std::sync::OnceLock;

/// How far apart two poses are, up to the object's symmetries ([`FitSetup::separation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Separation {
    /// The rotation between them, degrees.
    pub rotation_deg: f64,
    /// Their ADD, scene units.
    pub add: f64,
    /// Their ADD over the object's diameter.
    pub add_rel: f64,
}

/// The inputs of a fit, prepared once (module doc).
pub struct FitSetup {
    /// The mesh, with its edge topology and levels of detail.
    pub(crate) model: RenderMesh,
    /// The mesh clustered to cells of about two pixels at the search's resolution: what
    /// the search and the stages at or below its resolution render.
    pub(crate) search_model: RenderMesh,
    pub(crate) views: Vec<View>,
    pub(crate) windows: Vec<Window>,
    pub(crate) settings: FitSettings,
    /// The mesh's bounding-box centre (model frame).
    pub(crate) centre: DVec3,
    /// Half its bounding-box diagonal (model frame, > 0).
    pub(crate) radius: f64,
    /// The search's candidate rotations.
    pub(crate) rotations: Vec<DMat3>,
    /// The mesh's symmetries and its diameter (model frame), measured when first asked
    /// for ([`FitSetup::separation`]).
    shape: OnceLock<(Vec<DMat3>, f64)>,
}

impl FitSetup {
    /// Prepares a fit of `mesh` to `views` with `settings`.
    ///
    /// Errors: invalid settings or mesh, or no views.
    pub fn new(mesh: Mesh, views: Vec<View>, settings: FitSettings) -> Result<FitSetup> {
        settings.validate()?;
        if views.is_empty() {
            return Err(Error::Settings("at least one view is needed".into()));
        }
        mesh.validate("mesh")?;
        let b = mesh.bounds().ok_or_else(|| Error::Mesh {
            file: "mesh".into(),
            problem: "has no vertices".into(),
        })?;
        let windows = views.iter().map(|v| Window::for_view(v, settings.window)).collect();
        Ok(FitSetup {
            search_model: RenderMesh::exact(mesh.clustered(settings.search.resolution * 3 / 8)),
            model: RenderMesh::with_detail(mesh, settings.detail_px),
            rotations: settings.search.sampling.rotations(),
            centre: b.centre(),
            radius: (b.size().length() * 0.5).max(1e-12),
            views,
            windows,
            settings,
            shape: OnceLock::new(),
        })
    }

    /// How far apart two poses of the object are, up to its symmetries: the rotation
    /// between them (degrees) and their ADD over the object's diameter (at `a`'s mean
    /// scale), both taken at the symmetric equivalent of `b` closest to `a`.
    pub(crate) fn separation(&self, a: &Pose, b: &Pose) -> Separation {
        let mesh = self.mesh();
        let (syms, diameter) = self.shape.get_or_init(|| (symmetry::symmetries(mesh), mesh.diameter()));
        let b = symmetry::closest_equivalent(mesh, syms, a, b);
        let d = diameter * (a.scale.element_sum() / 3.0);
        let add = metrics::add(mesh, a, &b);
        Separation {
            rotation_deg: metrics::rotation_error_deg(a, &b),
            add,
            add_rel: if d > 0.0 { add / d } else { 0.0 },
        }
    }

    /// The mesh being fitted.
    pub fn mesh(&self) -> &Mesh {
        &self.model.mesh
    }

    /// The views.
    pub fn views(&self) -> &[View] {
        &self.views
    }

    /// Each view's window.
    pub fn windows(&self) -> &[Window] {
        &self.windows
    }

    /// The settings.
    pub fn settings(&self) -> &FitSettings {
        &self.settings
    }

    /// The mesh refinement stage `stage` renders: the search's clustered mesh at or below
    /// the search's resolution, the mesh (at its chosen level of detail) above.
    pub(crate) fn model_for(&self, stage: usize) -> &RenderMesh {
        if self.settings.stages[stage].resolution <= self.settings.search.resolution {
            &self.search_model
        } else {
            &self.model
        }
    }

    /// Candidate cameras ranked by how much a photograph from there is predicted to
    /// shrink the uncertainty of `pose` fitted with the views' `weights` (0: a view set
    /// aside), best first (`crate::uncertainty::next_view`): `candidates`, or
    /// [`next_view::SPHERE`] viewpoints over `shell` around the object. The one
    /// function behind [`Estimator::suggest_views`](super::Estimator::suggest_views),
    /// `suggest-view` and the page's `Session.suggestViews`. With `alternatives` (the
    /// poses of an `ambiguous` fit), the candidates that would best tell them apart come
    /// first ([`next_view::discriminate`]).
    ///
    /// Errors: the uncertainty cannot be measured, or a render fails.
    pub fn suggest_views(
        &self,
        pose: &Pose,
        weights: &[f64],
        alternatives: &[Pose],
        candidates: Option<&[Camera]>,
        shell: Viewpoints,
    ) -> Result<Vec<RankedView>> {
        let sphere;
        let candidates = match candidates {
            Some(c) => c,
            None => {
                sphere = candidate_viewpoints(&self.model, &self.views, pose, next_view::SPHERE, shell)?;
                &sphere
            }
        };
        let noise = NoiseModel::default();
        let u = fit_uncertainty(
            &self.model,
            &self.views,
            &self.windows,
            pose,
            weights,
            self.settings.scale_mode,
            &noise,
        )?;
        let mut ranked = rank_views(&self.model, pose, &u, candidates, &noise)?;
        next_view::discriminate(self.mesh(), pose, alternatives, &mut ranked);
        Ok(ranked)
    }

    /// The optimiser's length unit at `pose`: the object's radius in the world.
    pub(crate) fn length(&self, pose: &Pose) -> f64 {
        self.radius * pose.scale.max_element()
    }
}
