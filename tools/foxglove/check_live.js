// Watches aerotrack's live view with @foxglove/ws-protocol's client, the protocol's own implementation
// (issue 24 item 3): connects to ws://HOST:PORT with the foxglove.websocket.v1 subprotocol (retrying
// while the server starts), checks the server's info and its advertised channels (each protobuf
// schema a FileDescriptorSet that protobufjs loads), subscribes to TOPICS, and decodes every message
// it receives with its channel's schema, for SECONDS or until the server closes (the run is over), whichever
// comes first, so a topic that is late in a short run is still seen. One line out: what it received, or the
// first disagreement (status 1).
// usage: node check_live.js HOST:PORT SECONDS TOPIC [TOPIC...]
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { protobufFromBinaryDescriptor } = require("@mcap/support");
const WebSocket = require("ws");

function fail(message) {
  console.log(`live check: ${message}`);
  process.exit(1);
}

const [address, secondsText, ...topics] = process.argv.slice(2);
const seconds = Number(secondsText);
if (!address || !(seconds > 0) || topics.length === 0) fail("usage: node check_live.js HOST:PORT SECONDS TOPIC...");

function connect(triesLeft) {
  const ws = new WebSocket(`ws://${address}`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  ws.binaryType = "arraybuffer";
  ws.on("error", () => {});
  let opened = false;
  let finish;
  ws.on("close", () => {
    if (opened) finish();
    else if (triesLeft > 0) setTimeout(() => connect(triesLeft - 1), 200);
    else fail(`${address}: no server`);
  });
  ws.on("open", () => {
    opened = true;
    finish = run(ws);
  });
}

function run(ws) {
  const client = new FoxgloveClient({ ws });
  const decoders = new Map();  // subscription id -> (topic, decode)
  const counts = Object.fromEntries(topics.map((t) => [t, 0]));
  let serverName;
  client.on("serverInfo", (info) => {
    serverName = info.name;
  });
  client.on("advertise", (channels) => {
    for (const topic of topics) {
      const channel = channels.find((c) => c.topic === topic);
      if (channel == undefined) fail(`${topic} is not advertised (${channels.map((c) => c.topic).join(" ")})`);
      let decode;
      if (channel.encoding === "protobuf") {
        if (channel.schemaEncoding !== "protobuf") fail(`${topic}: schema encoding ${channel.schemaEncoding}`);
        const type = protobufFromBinaryDescriptor(Buffer.from(channel.schema, "base64")).lookupType(channel.schemaName);
        decode = (data) => type.toObject(type.decode(data));
      } else if (channel.encoding === "json") {
        decode = (data) => JSON.parse(new TextDecoder().decode(data));
      } else {
        fail(`${topic}: unknown encoding ${channel.encoding}`);
      }
      decoders.set(client.subscribe(channel.id), { topic, decode });
    }
  });
  client.on("message", ({ subscriptionId, data }) => {
    const d = decoders.get(subscriptionId);
    if (d == undefined) fail(`a message for subscription ${subscriptionId}, which was never made`);
    try {
      d.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
    } catch (e) {
      fail(`${d.topic}: a message does not decode: ${e.message}`);
    }
    ++counts[d.topic];
  });
  let finished = false;
  const finish = () => {
    if (finished) return;
    finished = true;
    client.close();
    if (serverName !== "aerotrack") fail(`server info: name ${serverName}`);
    const silent = topics.filter((t) => counts[t] === 0);
    if (silent.length > 0) fail(`no messages on ${silent.join(" ")}: ${JSON.stringify(counts)}`);
    const total = Object.values(counts).reduce((a, b) => a + b, 0);
    console.log(`live check: ${total} messages on ${topics.length} topics, all decoded: ${JSON.stringify(counts)}`);
    process.exit(0);
  };
  setTimeout(finish, seconds * 1000);
  return finish;
}

connect(50);
