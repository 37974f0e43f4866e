//! Rasterisation: the projection of the posed mesh (`project`), hard (binary)
//! silhouettes (`hard`), and soft silhouettes with their analytic backward passes —
//! the silhouette-edge rasteriser (`edge`, the default) and SoftRas (`softras`, the
//! cargo feature `softras`) — behind one interface (`silhouette`), which renders the
//! coarsest level of detail within a pixel tolerance (`lod`); `shade` renders
//! synthetic photographs.

pub mod edge;
pub mod hard;
pub mod lod;
pub mod project;
pub mod shade;
pub mod silhouette;
#[cfg(feature = "softras")]
pub mod softras;
