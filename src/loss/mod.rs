//! Losses between a rendered (soft) silhouette and a view's mask: IoU, contour
//! (Hausdorff), and the distance transform they use.

pub mod contour;
pub mod edt;
pub mod iou;
pub mod objective;
