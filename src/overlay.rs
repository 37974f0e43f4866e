//! Overlays: a view's image with the mask outline and the rendered contour. (Being written.)
