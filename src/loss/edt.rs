//! Exact Euclidean distance transform (Felzenszwalb & Huttenlocher, "Distance
//! Transforms of Sampled Functions", 2012): for every pixel, the distance in pixels
//! to the nearest seed pixel. Two 1-D passes of the lower envelope of parabolas.

/// Value used for "no seed": larger than any squared distance on a 16384² image.
const INF: f64 = 1e20;

/// Squared Euclidean distance from each pixel to the nearest pixel where `seed` is
/// true (`INF`-like 1e20 everywhere when there is no seed). Row-major, `w`×`h`.
pub fn squared_distance(w: usize, h: usize, seed: &[bool]) -> Vec<f64> {
    assert_eq!(seed.len(), w * h, "seed buffer must be w*h");
    let mut f: Vec<f64> = seed.iter().map(|&s| if s { 0.0 } else { INF }).collect();
    let n = w.max(h);
    let mut line = vec![0.0; n];
    let mut out = vec![0.0; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0.0; n + 1];
    // Columns.
    for x in 0..w {
        for y in 0..h {
            line[y] = f[y * w + x];
        }
        dt_1d(&line[..h], &mut out[..h], &mut v, &mut z);
        for y in 0..h {
            f[y * w + x] = out[y];
        }
    }
    // Rows.
    for y in 0..h {
        line[..w].copy_from_slice(&f[y * w..(y + 1) * w]);
        dt_1d(&line[..w], &mut out[..w], &mut v, &mut z);
        f[y * w..(y + 1) * w].copy_from_slice(&out[..w]);
    }
    f
}

/// Euclidean distance (not squared); see [`squared_distance`].
pub fn distance(w: usize, h: usize, seed: &[bool]) -> Vec<f64> {
    squared_distance(w, h, seed).into_iter().map(f64::sqrt).collect()
}

fn dt_1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    // Skip leading INF entries' parabolas: they never win against a finite one.
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        loop {
            let p = v[k];
            let s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[k] && k > 0 {
                k -= 1;
                continue;
            }
            if s <= z[k] {
                // k == 0: q replaces the first parabola.
                v[0] = q;
                z[0] = f64::NEG_INFINITY;
                z[1] = f64::INFINITY;
            } else {
                k += 1;
                v[k] = q;
                z[k] = s;
                z[k + 1] = f64::INFINITY;
            }
            break;
        }
    }
    let mut k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dx = q as f64 - p as f64;
        *dq = dx * dx + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(w: usize, h: usize, seed: &[bool]) -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                seed.iter()
                    .enumerate()
                    .filter(|(_, s)| **s)
                    .map(|(j, _)| {
                        let (a, b) = ((j % w) as f64, (j / w) as f64);
                        (x - a).powi(2) + (y - b).powi(2)
                    })
                    .fold(INF, f64::min)
            })
            .collect()
    }

    #[test]
    fn matches_brute_force() {
        let (w, h) = (23, 17);
        let mut state = 12345u32;
        for density in [2u32, 10, 60] {
            let seed: Vec<bool> = (0..w * h)
                .map(|_| {
                    state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                    (state >> 24).is_multiple_of(density)
                })
                .collect();
            assert_eq!(squared_distance(w, h, &seed), brute(w, h, &seed));
        }
        let one: Vec<bool> = (0..w * h).map(|i| i == 5 * w + 7).collect();
        let d = distance(w, h, &one);
        assert!((d[0] - (49.0f64 + 25.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn no_seed_is_far() {
        assert!(squared_distance(4, 3, &[false; 12]).iter().all(|&d| d >= 1e19));
    }
}
