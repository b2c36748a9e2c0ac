#!/usr/bin/python3
"""The Python half of the MoveNet fidelity check (tools/fidelity/run.sh drives it).

The converted ONNX models stop at the network's heads and leave decoding to the C++ detector,
so three things must agree with the original tfjs graph: the heads that OpenCV DNN computes from
the ONNX file, the decoding written down in scripts/models/README.md, and the C++ detector that
implements it. This tool provides the pieces that check them:

  inputs   letterbox real images (and video frames) into S x S PNGs, once, so that every runtime
           sees exactly the same pixels;
  decode   run an ONNX model in OpenCV DNN and decode its heads with a numpy transcription of the
           graph's tail (the reference decoder), printing what tfjs's Identity:0 would hold;
  heads    compare the ONNX heads (OpenCV) with the same tensors inside the tfjs graph, and both
           with a float64 numpy evaluation of the ONNX graph (its exact value);
  compare  compare reference.mjs's output with `decode` output or with `aerotrack detect --json`.

All arithmetic of the decoder is float32, in the order the graph does it.
"""
import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
import onnx
from numpy.lib.stride_tricks import sliding_window_view
from onnx import numpy_helper

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "scripts" / "models"))
import convert_movenet  # noqa: E402  (for the tfjs node names of the heads)

F32 = np.float32


# --- inputs -----------------------------------------------------------------------------------

def letterbox(image, size):
    """Scale the longer side to `size` and centre the image on a black square."""
    h, w = image.shape[:2]
    scale = size / max(h, w)
    nw, nh = max(1, round(w * scale)), max(1, round(h * scale))
    out = np.zeros((size, size, 3), np.uint8)
    y0, x0 = (size - nh) // 2, (size - nw) // 2
    out[y0:y0 + nh, x0:x0 + nw] = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_AREA)
    return out


def read_sources(path, frames):
    """(name, BGR image) for a still image, or for the chosen frames of a video."""
    path = Path(path)
    image = cv2.imread(str(path))
    if image is not None:
        yield path.stem, image
        return
    video = cv2.VideoCapture(str(path))
    for index in frames:
        video.set(cv2.CAP_PROP_POS_FRAMES, index)
        ok, frame = video.read()
        if not ok:
            raise SystemExit(f"fidelity: cannot read frame {index} of {path}")
        yield f"{path.stem}_f{index}", frame


def cmd_inputs(args):
    args.out.mkdir(parents=True, exist_ok=True)
    for source in args.images:
        for name, image in read_sources(source, args.frames):
            png = args.out / f"{name}_{args.size}.png"
            cv2.imwrite(str(png), letterbox(image, args.size))
            print(png)


# --- OpenCV DNN and the reference decoder ------------------------------------------------------

def run_onnx(net, heads, png):
    """The model's heads for one PNG, as {name: float32 [C,H,W]}."""
    image = cv2.imread(str(png))
    net.setInput(cv2.dnn.blobFromImage(image, 1.0, swapRB=True), "input")
    return {name: out[0] for name, out in zip(heads, net.forward(heads))}


def decode_singlepose(h, info):
    """Identity:0 of the singlepose graphs, [17][y, x, score], from the heads."""
    heatmap, regress, offset = h["heatmap"], h["regress"], h["offset"]
    size = info["heatmap_size"]
    bias = F32(info["distance_bias"])
    sy, sx = (F32(v) for v in info["coord_scale"])
    cy, cx = divmod(int(np.argmax(h["center"][0])), size)
    grid_y, grid_x = np.mgrid[0:size, 0:size].astype(F32)
    out = np.zeros((17, 3), F32)
    for k in range(17):
        ry = F32(cy) + regress[2 * k, cy, cx]
        rx = F32(cx) + regress[2 * k + 1, cy, cx]
        distance = np.sqrt((grid_y - ry) ** 2 + (grid_x - rx) ** 2) + bias
        y, x = divmod(int(np.argmax(heatmap[k] / distance)), size)
        out[k] = ((F32(y) + offset[2 * k, y, x]) * sy, (F32(x) + offset[2 * k + 1, y, x]) * sx,
                  heatmap[k, y, x])
    return out


def decode_multipose(h, info):
    """Identity:0 of the multipose graph, [6][17 x (y, x, score), ymin, xmin, ymax, xmax, score]."""
    size = info["heatmap_size"]
    center, heatmap = h["center"][0], h["heatmap"]
    persons = info["max_persons"]

    # Centres: local maxima of a k x k max pool (SAME: the window is cut at the border), top k.
    r = info["nms_kernel"] // 2
    padded = np.pad(center, r, constant_values=-np.inf)
    pooled = np.max([padded[dy:dy + size, dx:dx + size]
                     for dy in range(2 * r + 1) for dx in range(2 * r + 1)], axis=0)
    peaks = (center * (np.abs(center - pooled) < F32(info["nms_tolerance"])).astype(F32)).ravel()
    order = np.argsort(-peaks, kind="stable")[:persons]
    cy, cx = np.divmod(order, size)
    centre_score = peaks[order]

    # Boxes in heatmap cells, clipped to the map.
    scale = np.maximum(h["box_scale"][:, cy, cx], F32(info["box_scale_min"]))
    mid_y = cy.astype(F32) + h["box_offset"][0, cy, cx]
    mid_x = cx.astype(F32) + h["box_offset"][1, cy, cx]
    half = F32(info["box_half"])
    limit = F32(size)
    box = np.stack([np.clip(mid_y - scale[0] * half, 0, limit), np.clip(mid_x - scale[1] * half, 0, limit),
                    np.clip(mid_y + scale[0] * half, 0, limit), np.clip(mid_x + scale[1] * half, 0, limit)])

    # Keypoints: heatmap weighted by a Gaussian around each regressed joint, masked by the box.
    grid_y, grid_x = np.mgrid[0:size, 0:size].astype(F32)
    ry = cy.astype(F32)[:, None] + h["regress"][0::2, cy, cx].T  # [person, k]
    rx = cx.astype(F32)[:, None] + h["regress"][1::2, cy, cx].T
    d2 = (grid_y[:, :, None, None] - ry) ** 2 + (grid_x[:, :, None, None] - rx) ** 2
    sigma = F32(size) * F32(info["sigma_scale"])
    inside = ((grid_y[:, :, None] >= box[0]) & (grid_y[:, :, None] < box[2]) &
              (grid_x[:, :, None] >= box[1]) & (grid_x[:, :, None] < box[3])).astype(F32)
    weighted = heatmap.transpose(1, 2, 0)[:, :, None, :] * np.exp(-d2 / sigma) * inside[:, :, :, None]
    best = np.max(weighted, axis=2)  # [H, W, k]: the best person at each cell

    out = np.zeros((persons, 56), F32)
    coord_y, coord_x = (F32(v) for v in info["coord_scale"])
    stride = F32(info["output_stride"])
    threshold = F32(info["keypoint_threshold"])
    for p in range(persons):
        for k in range(17):
            y, x = divmod(int(np.argmax(weighted[:, :, p, k])), size)
            out[p, 3 * k:3 * k + 3] = ((F32(y) + h["offset"][2 * k, y, x]) * coord_y,
                                       (F32(x) + h["offset"][2 * k + 1, y, x]) * coord_x,
                                       best[y, x, k])
        out[p, 51:55] = np.clip(box[:, p] * stride / (stride * limit), 0, 1)
        scores = out[p, 2:51:3]
        count = max(F32(np.sum(scores > threshold)), F32(1))
        out[p, 55] = F32(1) / count * np.sum(centre_score[p] * np.where(scores > threshold, scores, 0))
    return out


def cmd_decode(args):
    info = json.loads(args.model.with_suffix(".decode.json").read_text())
    net = cv2.dnn.readNetFromONNX(str(args.model))
    decoder = decode_singlepose if info["variant"] == "singlepose" else decode_multipose
    for png in args.images:
        out = decoder(run_onnx(net, info["outputs"], png), info)
        print(json.dumps({"image": str(png), "output": out.tolist()}))


# --- heads against tfjs -------------------------------------------------------------------------

def run_onnx_float64(model, blob):
    """The ONNX graph evaluated in float64 with numpy (only the ops the converter emits): the
    exact value of the converted network, against which both float32 runtimes are measured."""
    env = {"input": blob.astype(np.float64)}
    env.update((t.name, numpy_helper.to_array(t).astype(np.float64)) for t in model.graph.initializer)
    for node in model.graph.node:
        attrs = {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}
        x, *rest = (env[name] for name in node.input)
        if node.op_type == "Conv":
            top, left, bottom, right = attrs["pads"]
            sh, sw = attrs["strides"]
            x = np.pad(x, ((0, 0), (0, 0), (top, bottom), (left, right)))
            windows = sliding_window_view(x, rest[0].shape[2:], axis=(2, 3))[:, :, ::sh, ::sw]
            if attrs["group"] == 1:
                y = np.einsum("nchwij,ocij->nohw", windows, rest[0], optimize=True)
            else:  # depthwise, multiplier 1
                y = np.einsum("nchwij,cij->nchw", windows, rest[0][:, 0])
            if len(rest) > 1:
                y = y + rest[1][None, :, None, None]
        elif node.op_type == "Relu":
            y = np.maximum(x, 0)
        elif node.op_type == "Clip":
            y = np.clip(x, attrs["min"], attrs["max"])
        elif node.op_type == "Sigmoid":
            y = 1 / (1 + np.exp(-x))
        elif node.op_type in ("Add", "Sub", "Mul"):
            y = {"Add": np.add, "Sub": np.subtract, "Mul": np.multiply}[node.op_type](x, rest[0])
        elif node.op_type == "Resize":
            y = x.repeat(2, axis=2).repeat(2, axis=3)
        elif node.op_type == "Pad":
            y = np.pad(x, ((0, 0), (0, 0), (1, 1), (1, 1)), mode="reflect")
        else:
            raise SystemExit(f"fidelity: no float64 evaluation of {node.op_type}")
        env[node.output[0]] = y
    return {out.name: env[out.name][0] for out in model.graph.output}


def cmd_heads(args):
    """Max abs difference per head between tfjs, OpenCV and the float64 evaluation, over the images."""
    info = json.loads(args.model.with_suffix(".decode.json").read_text())
    nodes = convert_movenet.Converter(json.loads(args.tfjs_model.read_text()), {}).head_nodes()
    net = cv2.dnn.readNetFromONNX(str(args.model))
    model = onnx.load(str(args.model))
    pairs = ("tfjs-opencv", "tfjs-float64", "opencv-float64")
    worst = {pair: {head: 0.0 for head in info["outputs"]} for pair in pairs}
    with tempfile.TemporaryDirectory() as dump:
        lines = subprocess.run(
            ["node", str(HERE / "reference.mjs"), "--model", str(args.tfjs_model), "--dump", dump,
             "--nodes", ",".join(nodes[head] for head in info["outputs"]), *map(str, args.images)],
            check=True, capture_output=True, text=True).stdout.splitlines()
        for line in lines:
            result = json.loads(line)
            opencv = run_onnx(net, info["outputs"], result["image"])
            exact = run_onnx_float64(model, cv2.dnn.blobFromImage(cv2.imread(result["image"]), 1.0, swapRB=True))
            for head, dumped in zip(info["outputs"], result["dumped"]):
                tfjs = np.fromfile(dumped["file"], F32).reshape(dumped["shape"])[0].transpose(2, 0, 1)
                for pair, a, b in zip(pairs, (tfjs, tfjs, opencv[head]), (opencv[head], exact[head], exact[head])):
                    worst[pair][head] = max(worst[pair][head], float(np.max(np.abs(a - b))))
    print(json.dumps({"model": str(args.model), "images": len(args.images), "max_abs_diff": worst}))


# --- comparison -----------------------------------------------------------------------------

def identity_persons(line):
    """tfjs Identity:0 (or `decode` output) as persons, each (coords, scores), normalised: coords are
    the keypoints' y, x (and the multipose box: ymin, xmin, ymax, xmax), scores the keypoints'
    scores (and the multipose person score)."""
    out = np.asarray(json.loads(line)["output"], np.float64)
    rows = out.reshape(-1, 56) if out.shape[-1] == 56 else out.reshape(1, 51)
    persons = []
    for row in rows:
        keypoints = row[:51].reshape(17, 3)
        persons.append((np.concatenate([keypoints[:, :2].ravel(), row[51:55]]),
                        np.concatenate([keypoints[:, 2], row[55:]])))
    return persons


def detect_persons(line, size, multipose):
    """`aerotrack detect --json` persons in the same form (pixels of the S x S PNG / S). Box and
    person score are the graph's only for multipose; singlepose ones are the detector's own."""
    persons = []
    for person in json.loads(line)["persons"]:
        x, y, score = np.asarray(person["keypoints"], np.float64).T
        coords, scores = np.stack([y, x], axis=1).ravel() / size, score
        if multipose:
            bx, by, bw, bh = np.asarray(person["bbox"], np.float64) / size
            coords = np.concatenate([coords, [by, bx, by + bh, bx + bw]])
            scores = np.append(scores, person["score"])
        persons.append((coords, scores))
    return persons


def cmd_compare(args):
    reference = args.reference.read_text().splitlines()
    candidate = args.candidate.read_text().splitlines()
    if len(reference) != len(candidate):
        raise SystemExit(f"fidelity: {len(reference)} reference results, {len(candidate)} to compare")
    coord = score = 0.0
    persons = 0
    for ref_line, cand_line in zip(reference, candidate):
        ref = identity_persons(ref_line)
        if args.format == "identity":  # same layout: each person against its counterpart
            pairs = list(zip(ref, identity_persons(cand_line), strict=True))
        else:  # each detected person against the reference person with the closest keypoints
            found = detect_persons(cand_line, args.size, multipose=len(ref) > 1)
            pairs = [(min(ref, key=lambda r: np.max(np.abs(r[0][:34] - f[0][:34]))), f) for f in found]
        for (ref_coords, ref_scores), (coords, scores) in pairs:
            coord = max(coord, float(np.max(np.abs(coords - ref_coords))))
            score = max(score, float(np.max(np.abs(scores - ref_scores))))
        persons += len(pairs)
    ok = coord <= args.tolerance and score <= args.tolerance and persons > 0
    print(f"{args.label}: {len(reference)} images, {persons} persons, max |d coord| {coord:.2e}, "
          f"max |d score| {score:.2e}  {'ok' if ok else 'FAIL'} (tolerance {args.tolerance:g})")
    sys.exit(0 if ok else 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("inputs", help="letterbox images / video frames into S x S PNGs")
    p.add_argument("--size", type=int, required=True)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--frames", type=lambda s: [int(i) for i in s.split(",")], default=[0, 200, 400])
    p.add_argument("images", nargs="+")
    p.set_defaults(run=cmd_inputs)
    p = sub.add_parser("decode", help="OpenCV DNN + reference decoder, tfjs Identity:0 layout")
    p.add_argument("--model", type=Path, required=True, help="models/movenet-<variant>.onnx")
    p.add_argument("images", nargs="+", type=Path)
    p.set_defaults(run=cmd_decode)
    p = sub.add_parser("heads", help="ONNX heads in OpenCV against the tfjs graph's tensors")
    p.add_argument("--model", type=Path, required=True)
    p.add_argument("--tfjs-model", type=Path, required=True)
    p.add_argument("images", nargs="+", type=Path)
    p.set_defaults(run=cmd_heads)
    p = sub.add_parser("compare", help="keypoints of reference.mjs against a candidate")
    p.add_argument("--reference", type=Path, required=True)
    p.add_argument("--candidate", type=Path, required=True)
    p.add_argument("--format", choices=["identity", "detect"], required=True)
    p.add_argument("--size", type=int, required=True, help="the PNGs' side in pixels")
    p.add_argument("--tolerance", type=float, default=1e-4)
    p.add_argument("--label", default="fidelity")
    p.set_defaults(run=cmd_compare)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
