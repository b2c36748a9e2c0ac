// Decodes frames made by aerotrack's MAVLink codec (tests/tools/mavlink_frames.cpp) with node-mavlink,
// an independent implementation, and compares every field with the value our side encoded (issue 11
// item 4). Reads "NAME HEX {json}" lines on stdin; prints one summary line; exits 1 on any mismatch,
// CRC error (node-mavlink checks our CRC_EXTRA), unknown or missing frame.
// usage: mavlink_frames | node check.js      (tools/mavlink/check.sh installs node-mavlink first)
const { MavLinkPacketSplitter, MavLinkPacketParser, minimal, common } = require('node-mavlink');
const readline = require('readline');

const registry = { ...minimal.REGISTRY, ...common.REGISTRY };
const expected = [];
const problems = [];
let crcErrors = 0;

const splitter = new MavLinkPacketSplitter({}, { onCrcError: () => { crcErrors += 1; } });
const packets = [];
splitter.pipe(new MavLinkPacketParser()).on('data', (packet) => packets.push(packet));

// Floats travel as float32: what we encoded is the float nearest the printed value.
function same(want, got) {
  if (Array.isArray(want)) return Array.isArray(got) && want.length === got.length && want.every((w, i) => same(w, got[i]));
  if (typeof got === 'bigint') return BigInt(want) === got;
  return Math.fround(want) === got || want === got;
}

readline.createInterface({ input: process.stdin }).on('line', (line) => {
  const [name, hex, ...json] = line.split(' ');
  expected.push({ name, fields: JSON.parse(json.join(' ')) });
  splitter.write(Buffer.from(hex, 'hex'));
}).on('close', () => {
  splitter.end();
  setImmediate(() => {
    if (packets.length !== expected.length) problems.push(`${expected.length} frames written, ${packets.length} decoded`);
    packets.forEach((packet, i) => {
      const want = expected[i];
      const clazz = registry[packet.header.msgid];
      if (!clazz) return problems.push(`frame ${i}: unknown message id ${packet.header.msgid}`);
      if (clazz.MSG_NAME !== want.name) return problems.push(`frame ${i}: ${clazz.MSG_NAME}, expected ${want.name}`);
      const data = packet.protocol.data(packet.payload, clazz);
      for (const [field, value] of Object.entries(want.fields)) {
        if (!same(value, data[field])) problems.push(`frame ${i} ${want.name}.${field}: node-mavlink ${data[field]}, ours ${JSON.stringify(value)}`);
      }
      if (packet.header.sysid !== 1 || packet.header.compid !== 191) problems.push(`frame ${i}: sender ${packet.header.sysid}/${packet.header.compid}`);
    });
    if (crcErrors > 0) problems.push(`${crcErrors} CRC errors`);
    if (problems.length > 0) {
      console.log(`node-mavlink disagrees: ${problems[0]} (${problems.length} problems)`);
      process.exit(1);
    }
    const names = [...new Set(expected.map((e) => e.name))].join(', ');
    console.log(`node-mavlink decoded all ${packets.length} frames identically (${names})`);
  });
});
