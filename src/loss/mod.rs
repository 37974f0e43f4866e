//! Losses between a rendered (soft) silhouette and a view's mask: the targets (a
//! view's mask in its window at a resolution), the soft IoU, the contour (chamfer)
//! term and the distance transform it uses, the region (colour posterior) term, and the
//! one multi-view objective.

pub mod contour;
pub mod edt;
pub mod iou;
pub mod objective;
pub mod region;
pub mod target;
