//! The segmenter's unit tests (those that need no weights).

use crate::grid::*;
use crate::*;

#[test]
fn hashes_are_checked_and_named() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    let e = check_hash("enc.onnx", b"abc", ENCODER_SHA256).unwrap_err().to_string();
    assert!(
        e.contains("enc.onnx") && e.contains(PACKAGE) && e.contains("altered"),
        "{e}"
    );
    let e = Sam::new(b"not onnx", b"", ["a.onnx", "b.onnx"])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("a.onnx"), "{e}");
    // Chunked hashing is the one-call hash, across chunk boundaries.
    let big: Vec<u8> = (0..(3 << 16) + 17).map(|i| (i * 7 % 251) as u8).collect();
    assert_eq!(
        sha256_hex(&big),
        Sha256::digest(&big)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect::<String>()
    );
}

#[test]
fn digests_a_caller_found_are_checked_not_the_bytes() {
    // A digest that is not the pinned one: refused, naming the file and the digest.
    let e = Sam::with_digests(b"", b"", ["enc.onnx", "dec.onnx"], ["00ff", DECODER_SHA256])
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("enc.onnx") && e.contains("00ff") && e.contains(ENCODER_SHA256),
        "{e}"
    );
    let e = check_digest("dec.onnx", "abc", DECODER_SHA256).unwrap_err().to_string();
    assert!(e.contains("dec.onnx") && e.contains("abc"), "{e}");
    assert!(check_digest("dec.onnx", DECODER_SHA256, DECODER_SHA256).is_ok());
    // The pinned digests pass the check: what fails then is the engine, on bytes
    // that are no model.
    let e = Sam::with_digests(
        b"not onnx",
        b"",
        ["enc.onnx", "dec.onnx"],
        [ENCODER_SHA256, DECODER_SHA256],
    )
    .err()
    .unwrap();
    assert!(matches!(e, SegmentError::Engine(_)), "{e}");
}

#[test]
fn a_box_alone_takes_the_single_mask_output_else_the_exports_rule() {
    let scores = [0.90, 0.80, 0.95, 0.70];
    // A box alone: the single-mask output, though a multimask one scores higher.
    assert_eq!(preferred(&scores, 2, true), 0);
    // One point (and the padding point): the best multimask output.
    assert_eq!(preferred(&scores, 2, false), 2);
    // A box and a point, or three points: the single-mask output.
    assert_eq!(preferred(&scores, 3, true), 0);
    assert_eq!(preferred(&scores, 3, false), 0);
}

#[test]
fn upscaling_keeps_a_constant_and_a_ramp_s_midpoint() {
    let flat = vec![2.0f32; LOW_RES * LOW_RES];
    assert!(upscale(&flat, 96, Region::FULL).iter().all(|&v| (v - 2.0).abs() < 1e-6));
    // A left-to-right ramp crosses zero in the middle column at any output size.
    let ramp: Vec<f32> = (0..LOW_RES * LOW_RES).map(|i| (i % LOW_RES) as f32 - 127.5).collect();
    let up = upscale(&ramp, 100, Region::FULL);
    let row = &up[50 * 100..51 * 100];
    let crossing = row.iter().position(|&v| v > 0.0).unwrap();
    assert!((49..=51).contains(&crossing), "{crossing}");
}

/// A pattern's value at the crop's own 256² cell `(x, y)`: a step that is 5 left
/// of column 96, -5 right of it (a mask's edge), plus a gentle vertical ramp.
fn pattern(x: usize, y: usize) -> f32 {
    (if x < 96 { 5.0 } else { -5.0 }) + y as f32 / 64.0
}

#[test]
fn a_tile_s_logits_go_to_its_quarter_and_come_back() {
    let crop: Vec<f32> = (0..LOW_RES * LOW_RES)
        .map(|i| pattern(i % LOW_RES, i / LOW_RES))
        .collect();
    assert_eq!(to_input_grid(&crop, Region::FULL), crop);
    assert_eq!(from_input_grid(&crop, Region::FULL), crop);
    for k in 0..MAX_TILES {
        let r = Region::tile(k);
        let grid = to_input_grid(&crop, r);
        // Outside the tile's quarter: background; inside: the crop, halved.
        let (gx, gy, n) = (r.x0 / GRID, r.y0 / GRID, r.size / GRID);
        assert_eq!(n, LOW_RES / 2);
        for y in 0..LOW_RES {
            for x in 0..LOW_RES {
                let inside = (gx..gx + n).contains(&x) && (gy..gy + n).contains(&y);
                let v = grid[y * LOW_RES + x];
                if !inside {
                    assert_eq!(v, BACKGROUND_LOGIT, "tile {k} at ({x}, {y})");
                } else {
                    // The step sits at half the column in the quarter.
                    let left = x - gx < 47;
                    let right = x - gx > 49;
                    assert!(!left || v > 0.0, "tile {k} at ({x}, {y}): {v}");
                    assert!(!right || v < 0.0, "tile {k} at ({x}, {y}): {v}");
                }
            }
        }
        // Back from the quarter: the same mask (sign) away from the step's
        // resampling band, the ramp within a cell.
        let back = from_input_grid(&grid, r);
        for y in 0..LOW_RES {
            for x in (0..LOW_RES).filter(|x| !(92..100).contains(x)) {
                let (a, b) = (back[y * LOW_RES + x], crop[y * LOW_RES + x]);
                assert_eq!(a > 0.0, b > 0.0, "tile {k} at ({x}, {y}): {a} vs {b}");
                if !(88..104).contains(&x) {
                    assert!((a - b).abs() < 0.05, "tile {k} at ({x}, {y}): {a} vs {b}");
                }
            }
        }
    }
}

#[test]
fn a_crop_is_placed_in_its_tile_only() {
    let (side, plane) = (64u32, INPUT * INPUT);
    let white = vec![255u8; (side * side * 3) as usize];
    let mut data = vec![0f32; 3 * plane];
    place(&mut data, &white, side, Region::tile(3)).unwrap();
    for c in 0..3 {
        let want = (255.0 - MEAN[c]) / STD[c];
        for (y, x) in [(0, 0), (TILE - 1, TILE - 1), (TILE - 1, INPUT - 1), (INPUT - 1, 0)] {
            assert_eq!(data[c * plane + y * INPUT + x], 0.0, "outside tile 3 at ({x}, {y})");
        }
        for (y, x) in [(TILE, TILE), (INPUT - 1, INPUT - 1), (TILE + 7, INPUT - 3)] {
            assert!(
                (data[c * plane + y * INPUT + x] - want).abs() < 1e-5,
                "tile 3 at ({x}, {y})"
            );
        }
    }
    let e = place(&mut data, &white[..10], side, Region::tile(0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("10 bytes"), "{e}");
}
