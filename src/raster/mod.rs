//! Rasterisation: the projection of the posed mesh (`project`), hard (binary)
//! silhouettes (`hard`), and soft silhouettes with their analytic backward passes —
//! the silhouette-edge rasteriser (`edge`, the default) and SoftRas (`tiles`, `soft`,
//! `soft_backward`) — behind one interface (`silhouette`), which renders the
//! coarsest level of detail within a pixel tolerance (`lod`); `shade` renders
//! synthetic photographs.

pub mod edge;
pub mod hard;
pub mod lod;
pub mod project;
pub mod shade;
pub mod silhouette;
pub mod soft;
pub mod soft_backward;
mod tiles;
