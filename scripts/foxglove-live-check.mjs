// Watches a Foxglove WebSocket server with the official client library
// (npm @foxglove/ws-protocol) and prints what it saw as JSON: the server's
// name, every advertised channel with its schema, and per topic how many
// messages arrived and the first of them, parsed.
//
//   node foxglove-live-check.mjs ws://127.0.0.1:PORT SECONDS [--stall]
//
// Subscribes to every channel. Stops after SECONDS, or once the server
// closes. With --stall it stops reading after the first message, as a
// viewer on a slow link would (the server must not wait for it), and says
// "stalled" on stderr when it does.
import { createRequire } from "node:module";

// The packages live where foxglove-live-check.sh installed them.
const require = createRequire(process.env.FOXGLOVE_CLIENT_DIR + "/package.json");
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const [url, seconds, mode] = process.argv.slice(2);
const stall = mode === "--stall";
// The foxglove crate's server speaks the SDK subprotocol; the client
// parses both it and the older one.
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL, "foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const seen = { server: null, subprotocol: null, channels: [], received: {}, first: {}, errors: [] };
const topicOf = new Map();
const decoder = new TextDecoder();

client.on("serverInfo", (info) => {
  seen.server = info.name;
  seen.subprotocol = ws.protocol;
});
client.on("advertise", (channels) => {
  for (const channel of channels) {
    seen.channels.push({
      topic: channel.topic,
      encoding: channel.encoding,
      schemaName: channel.schemaName,
      schemaEncoding: channel.schemaEncoding,
      schema: JSON.parse(channel.schema),
    });
    topicOf.set(client.subscribe(channel.id), channel.topic);
  }
});
client.on("message", ({ subscriptionId, data }) => {
  const topic = topicOf.get(subscriptionId);
  seen.received[topic] = (seen.received[topic] ?? 0) + 1;
  if (!(topic in seen.first)) {
    try {
      seen.first[topic] = JSON.parse(decoder.decode(data));
    } catch (e) {
      seen.errors.push(`${topic}: ${e.message}`);
    }
  }
  if (stall && !ws._socket.isPaused()) {
    ws._socket.pause();
    process.stderr.write("stalled\n");
  }
});
client.on("error", (e) => seen.errors.push(String(e?.message ?? e)));

const finish = () => {
  process.stdout.write(JSON.stringify(seen) + "\n");
  process.exit(0);
};
client.on("close", finish);
setTimeout(finish, Number(seconds) * 1000);
