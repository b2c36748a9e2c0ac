// Reads an MCAP file with @mcap/core, the independent reader (issue 24 item 3), and checks it:
// the summary (indexed reader: it seeks through the chunk and message indexes), the whole file
// streamed with every chunk CRC validated, the data section's CRC, the statistics against the
// messages read, and every message decoded with its own schema (protobuf through protobufjs from the
// FileDescriptorSet in the file; JSON parsed). One line out: what it read, or the first disagreement
// (status 1). With --json: {"messages":N,"chunks":C,"topics":{"/topic":{"schema":..,"encoding":..,"count":n}}}.
// With --cut: a log that stopped early (a full disk) and has no summary: it is streamed, every chunk's CRC
// checked, and it must end after a whole record.
// usage: node check_mcap.js FILE [--json | --cut]
"use strict";
const fs = require("fs");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { loadDecompressHandlers, protobufFromBinaryDescriptor } = require("@mcap/support");
const { crc32 } = require("@foxglove/crc");

function fail(message) {
  console.log(`mcap check: ${message}`);
  process.exit(1);
}

async function main() {
  const [file, flag] = process.argv.slice(2);
  if (!file) fail("usage: node check_mcap.js FILE [--json]");
  let bytes;
  try {
    bytes = fs.readFileSync(file);
  } catch (e) {
    fail(`${file}: ${e.message}`);
  }
  const decompressHandlers = await loadDecompressHandlers();
  if (flag === "--cut") return checkCut(file, bytes, decompressHandlers);
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  if (reader.statistics == undefined) fail(`${file}: no statistics in the summary`);
  if (reader.dataSectionCrc != undefined && reader.dataSectionCrc !== 0) {
    const crc = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
    if (crc !== reader.dataSectionCrc) fail(`${file}: data section CRC ${crc} != ${reader.dataSectionCrc}`);
  }
  const decoders = new Map();
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    if (channel.messageEncoding === "protobuf") {
      if (schema == undefined || schema.encoding !== "protobuf") fail(`${channel.topic}: protobuf without a protobuf schema`);
      const type = protobufFromBinaryDescriptor(schema.data).lookupType(schema.name);
      decoders.set(id, (data) => type.toObject(type.decode(data), { defaults: false }));
    } else if (channel.messageEncoding === "json") {
      decoders.set(id, (data) => JSON.parse(new TextDecoder().decode(data)));
    } else {
      decoders.set(id, () => null);
    }
  }
  const topics = {};
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    topics[channel.topic] = { schema: schema ? schema.name : "", encoding: channel.messageEncoding, count: 0 };
  }
  let indexed = 0;
  let lastTime = -1n;
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    const channel = reader.channelsById.get(message.channelId);
    try {
      decoders.get(message.channelId)(message.data);
    } catch (e) {
      fail(`${channel.topic}: message ${message.sequence} does not decode: ${e.message}`);
    }
    if (message.logTime < lastTime) fail(`${channel.topic}: messages out of log-time order`);
    lastTime = message.logTime;
    ++topics[channel.topic].count;
    ++indexed;
  }
  const stats = reader.statistics;
  if (BigInt(indexed) !== stats.messageCount) fail(`read ${indexed} messages, the statistics say ${stats.messageCount}`);
  for (const [id, count] of stats.channelMessageCounts) {
    const topic = reader.channelsById.get(id).topic;
    if (BigInt(topics[topic].count) !== count) fail(`${topic}: read ${topics[topic].count}, the statistics say ${count}`);
  }
  // The same file streamed from its first byte, every chunk's CRC checked.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  let streamed = 0;
  let record;
  while ((record = stream.nextRecord()) != undefined) {
    if (record.type === "Message") ++streamed;
  }
  if (!stream.done()) fail(`${file}: the stream reader did not reach the end magic`);
  if (streamed !== indexed) fail(`streamed ${streamed} messages, indexed ${indexed}`);
  const channels = Object.keys(topics).length;
  if (flag === "--json") {
    console.log(JSON.stringify({ messages: indexed, chunks: reader.chunkIndexes.length, topics }));
  } else {
    console.log(`mcap check: ${indexed} messages on ${channels} channels in ${reader.chunkIndexes.length} chunks; ` +
      "all decoded; indexes, CRCs and statistics agree");
  }
}

function checkCut(file, bytes, decompressHandlers) {
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  let messages = 0;
  let chunks = 0;
  let record;
  while ((record = stream.nextRecord()) != undefined) {
    if (record.type === "Message") ++messages;
    if (record.type === "Footer") fail(`${file}: has a footer: not a cut log`);
  }
  if (stream.bytesRemaining() !== 0) fail(`${file}: ends inside a record (${stream.bytesRemaining()} bytes left over)`);
  const reader = new McapStreamReader({ includeChunks: true, decompressHandlers });
  reader.append(bytes);
  while ((record = reader.nextRecord()) != undefined) if (record.type === "Chunk") ++chunks;
  console.log(`mcap check: a cut log, ${messages} messages in ${chunks} whole chunks, every CRC valid`);
}

main().catch((e) => fail(e.message));
