//! Soft IoU loss between a soft silhouette A ∈ [0, 1] and a binary mask M ∈ {0, 1}
//! (SPEC §4 "Losses"; the PyTorch3D reference case's loss):
//! `L = 1 − Σ A·M / (Σ (A + M − A·M) + 1e-6)`, and its gradient ∂L/∂A per pixel.
//!
//! Inputs are row-major per-pixel slices of equal length (alpha as f64, the mask as
//! bytes, non-zero meaning object).

/// The constant added to the union (as in the reference case), keeping L finite for
/// an empty render against an empty mask.
pub const UNION_EPS: f64 = 1e-6;

/// Intersection `I = Σ A·M` and union `U = Σ (A + M − A·M) + 1e-6`; the loss is
/// `1 − I/U` and `∂L/∂A_p = I/U² − M_p·(1/U + I/U²)`.
///
/// # Panics
/// If `alpha` and `mask` differ in length.
pub fn soft_iou_sums(alpha: &[f64], mask: &[u8]) -> (f64, f64) {
    assert_eq!(alpha.len(), mask.len(), "alpha and mask must have the same length");
    let (mut inter, mut sum_a, mut sum_m) = (0.0, 0.0, 0.0);
    for (&a, &m) in alpha.iter().zip(mask) {
        sum_a += a;
        if m != 0 {
            inter += a;
            sum_m += 1.0;
        }
    }
    (inter, sum_a + sum_m - inter + UNION_EPS)
}

/// The soft IoU loss `1 − Σ A·M / (Σ (A + M − A·M) + 1e-6)`, in [0, 1].
///
/// # Panics
/// If `alpha` and `mask` differ in length.
pub fn soft_iou_loss(alpha: &[f64], mask: &[u8]) -> f64 {
    let (i, u) = soft_iou_sums(alpha, mask);
    1.0 - i / u
}

/// The soft IoU loss, and `scale·∂L/∂A_p` added to `grad[p]` for every pixel:
/// `∂L/∂A_p = −(M_p·U − I·(1 − M_p)) / U²` (I, U as in [`soft_iou_loss`]).
///
/// # Panics
/// If `alpha`, `mask` and `grad` differ in length.
pub fn soft_iou_loss_grad(alpha: &[f64], mask: &[u8], scale: f64, grad: &mut [f64]) -> f64 {
    assert_eq!(alpha.len(), grad.len(), "alpha and grad must have the same length");
    let (i, u) = soft_iou_sums(alpha, mask);
    let g_in = -scale / u;
    let g_out = scale * i / (u * u);
    for (g, &m) in grad.iter_mut().zip(mask) {
        *g += if m != 0 { g_in } else { g_out };
    }
    1.0 - i / u
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_and_disjoint() {
        let m = [1u8, 1, 0, 0];
        assert!(soft_iou_loss(&[1.0, 1.0, 0.0, 0.0], &m) < 1e-6);
        assert!((soft_iou_loss(&[0.0, 0.0, 1.0, 1.0], &m) - 1.0).abs() < 1e-12);
        // Half overlap: I = 1, U = 3.
        assert!((soft_iou_loss(&[1.0, 0.0, 1.0, 0.0], &m) - (1.0 - 1.0 / (3.0 + 1e-6))).abs() < 1e-12);
    }

    #[test]
    fn gradient_matches_central_differences() {
        let m: Vec<u8> = (0..40).map(|i| ((i * 7) % 5 < 2) as u8).collect();
        let a: Vec<f64> = (0..40).map(|i| (i as f64 * 0.37).sin() * 0.5 + 0.5).collect();
        let mut g = vec![0.5; 40];
        let l = soft_iou_loss_grad(&a, &m, 2.0, &mut g);
        assert!((l - soft_iou_loss(&a, &m)).abs() < 1e-15);
        let h = 1e-6;
        for p in 0..40 {
            let mut ap = a.clone();
            ap[p] += h;
            let mut am = a.clone();
            am[p] -= h;
            let fd = (soft_iou_loss(&ap, &m) - soft_iou_loss(&am, &m)) / (2.0 * h);
            // grad started at 0.5 and received 2·∂L/∂A.
            assert!(
                (g[p] - 0.5 - 2.0 * fd).abs() < 1e-8,
                "pixel {p}: {} vs {}",
                g[p] - 0.5,
                2.0 * fd
            );
        }
    }
}
