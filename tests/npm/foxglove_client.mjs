// A Foxglove WebSocket client written by others (@foxglove/ws-protocol's FoxgloveClient over `ws`),
// pointed at shapeform_view --foxglove-port: connects one client per subprotocol given, all at once,
// subscribes each to the channels named, decodes cdr with the advertised omgidl schema
// (@foxglove/omgidl-parser + @foxglove/omgidl-serialization) and json with JSON.parse, and prints what
// it received as JSON lines on stdout. Test-time only; the packages come from build/npm
// (scripts/install_deps.sh).
//
// node tests/npm/foxglove_client.mjs --url ws://127.0.0.1:P [--npm DIR] [--subprotocols a,b]
//        [--topics shapeform/scene,shapeform/state,...] [--count N] [--timeout S] [--refused-check] [--brief]
// --brief: each message line carries its size, receive time (recv_ms) and the scene's sphere count only.
// --stalled N: N more clients subscribe to the same topics and then stop reading their socket (a slow
// client: the server must drop messages for them, not stall the others).
// Exits 0 when every client got at least N messages of every topic named that is advertised, 1 on a
// timeout or an error (saying which), 2 on bad arguments or missing packages.
import { createRequire } from "node:module";
import { existsSync } from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const args = { url: "", npm: path.resolve(here, "../../build/npm"), subprotocols: "foxglove.sdk.v1,foxglove.websocket.v1",
               topics: "shapeform/scene", count: 5, timeout: 30, refusedCheck: false, unsupportedOp: true, brief: false, stalled: 0 };
for (let i = 2; i < process.argv.length; ++i) {
  const a = process.argv[i];
  const next = () => { if (i + 1 >= process.argv.length) bad(`${a} needs a value`); return process.argv[++i]; };
  if (a === "--url") args.url = next();
  else if (a === "--npm") args.npm = path.resolve(next());
  else if (a === "--subprotocols") args.subprotocols = next();
  else if (a === "--topics") args.topics = next();
  else if (a === "--count") args.count = Number(next());
  else if (a === "--timeout") args.timeout = Number(next());
  else if (a === "--refused-check") args.refusedCheck = true;
  else if (a === "--brief") args.brief = true;  // per message: sizes and counts only (benchmarks)
  else if (a === "--stalled") args.stalled = Number(next());
  else if (a === "--help" || a === "-h") { console.log("usage: node foxglove_client.mjs --url ws://HOST:PORT [--npm DIR] [--subprotocols a,b] [--topics t1,t2] [--count N] [--timeout S] [--refused-check] [--brief]"); process.exit(0); }
  else bad(`unknown argument ${a}`);
}
function bad(msg) { console.error(`foxglove_client: ${msg}`); process.exit(2); }
if (!args.url) bad("--url ws://HOST:PORT is required");
if (!existsSync(path.join(args.npm, "node_modules", "@foxglove", "ws-protocol"))) {
  bad(`the npm validators are missing in ${args.npm}: run scripts/install_deps.sh (it installs tests/npm/package-lock.json there)`);
}
const require = createRequire(path.join(args.npm, "package.json"));
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

const out = (o) => process.stdout.write(JSON.stringify(o) + "\n");
const wanted = args.topics.split(",").filter(Boolean);
const protocols = args.subprotocols.split(",").filter(Boolean);
let failed = false;
const fail = (msg) => { if (!failed) { failed = true; console.error(`foxglove_client: ${msg}`); } };

/// A decoder per channel: cdr through the omgidl schema, json through JSON.parse.
function decoderOf(channel) {
  if (channel.encoding === "json") return (bytes) => JSON.parse(new TextDecoder().decode(bytes));
  if (channel.encoding === "cdr" && channel.schemaEncoding === "omgidl") {
    const reader = new MessageReader(channel.schemaName, parseIDL(channel.schema));
    return (bytes) => reader.readMessage(bytes);
  }
  throw new Error(`channel ${channel.topic}: no decoder for ${channel.encoding}/${channel.schemaEncoding}`);
}

/// What a test needs of a message, short: agent positions of the scene, the states of state topics.
function summary(topic, m) {
  if (topic === "shapeform/scene") {
    const agents = m.entities.find((e) => e.id === "agents");
    return { frame_id: agents.frame_id, spheres: agents.spheres.map((s) => [s.pose.position.x, s.pose.position.y]),
             colors: agents.spheres.map((s) => [s.color.r, s.color.g, s.color.b, s.color.a]),
             entities: m.entities.map((e) => e.id) };
  }
  if (topic === "shapeform/agent_poses") return { frame_id: m.frame_id, poses: m.poses.length };
  const state = (s) => ({ id: s.id, model_time: s.model_time, x: s.x, y: s.y });
  if (topic === "shapeform/state") return { states: [state(m)] };
  if (topic === "shapeform/state_batch") return { states: m.states.map(state) };
  return { keys: Object.keys(m).slice(0, 8) };
}

function runClient(protocol, index) {
  return new Promise((resolve) => {
    const ws = new WebSocket(args.url, [protocol]);
    const client = new FoxgloveClient({ ws });
    const counts = new Map();
    const subs = new Map();  // subscription id -> { topic, decode }
    let advertised = [];
    const done = () => advertised.length > 0 && advertised.every((t) => (counts.get(t) ?? 0) >= args.count);
    let finished = false;
    const finish = (ok) => { if (finished) return; finished = true; clearTimeout(timer); client.close(); resolve(ok); };
    const timer = setTimeout(() => {
      fail(`client ${index} (${protocol}): timed out after ${args.timeout} s; received ${JSON.stringify(Object.fromEntries(counts))}`);
      finish(false);
    }, args.timeout * 1000);
    client.on("open", () => out({ event: "open", client: index, protocol: ws.protocol }));
    client.on("error", (e) => { fail(`client ${index} (${protocol}): ${e?.message ?? e}`); finish(false); });
    client.on("serverInfo", (info) => out({ event: "serverInfo", client: index, name: info.name, capabilities: info.capabilities }));
    client.on("status", (s) => out({ event: "status", client: index, level: s.level, message: s.message }));
    client.on("advertise", (channels) => {
      out({ event: "advertise", client: index, channels: channels.map((c) => ({ id: c.id, topic: c.topic, encoding: c.encoding,
            schemaName: c.schemaName, schemaEncoding: c.schemaEncoding })) });
      for (const c of channels) {
        if (!wanted.includes(c.topic)) continue;
        let decode;
        try { decode = decoderOf(c); } catch (e) { fail(e.message); finish(false); return; }
        subs.set(client.subscribe(c.id), { topic: c.topic, decode });
        advertised.push(c.topic);
      }
      // A read-only server answers what it does not serve with a status (printed above).
      if (args.unsupportedOp && index === 0) client.getParameters([], "p");
    });
    client.on("message", ({ subscriptionId, timestamp, data }) => {
      const s = subs.get(subscriptionId);
      if (!s) { fail(`client ${index}: a message for unknown subscription ${subscriptionId}`); return; }
      let m;
      try { m = s.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength)); }
      catch (e) { fail(`client ${index}: ${s.topic}: cannot decode: ${e.message}`); finish(false); return; }
      counts.set(s.topic, (counts.get(s.topic) ?? 0) + 1);
      const line = { event: "message", client: index, protocol, topic: s.topic, timestamp: timestamp.toString(), bytes: data.byteLength };
      if (args.brief) {
        line.recv_ms = performance.now();
        if (s.topic === "shapeform/scene") line.spheres = m.entities.find((e) => e.id === "agents").spheres.length;
        out(line);
      } else {
        out({ ...line, ...summary(s.topic, m) });
      }
      if (done()) finish(true);
    });
    client.on("close", () => { if (!finished) { fail(`client ${index} (${protocol}): closed by the server`); finish(false); } });
  });
}

/// A client asking for no known subprotocol must be refused.
function refusedCheck() {
  return new Promise((resolve) => {
    const ws = new WebSocket(args.url, ["not.foxglove"]);
    ws.on("open", () => { fail("a connection without a Foxglove subprotocol was accepted"); ws.close(); resolve(false); });
    ws.on("unexpected-response", (req, res) => { out({ event: "refused", status: res.statusCode }); req.destroy(); resolve(true); });
    ws.on("error", (e) => { out({ event: "refused", error: e.message }); resolve(true); });
  });
}

/// A client that subscribes, then never reads again.
function stalledClient(index) {
  const ws = new WebSocket(args.url, ["foxglove.websocket.v1"]);
  const client = new FoxgloveClient({ ws });
  client.on("error", () => {});
  client.on("advertise", (channels) => {
    for (const c of channels) if (wanted.includes(c.topic)) client.subscribe(c.id);
    setTimeout(() => { ws._socket.pause(); out({ event: "stalled", client: index }); }, 200);
  });
  return ws;
}
const stalled = Array.from({ length: args.stalled }, (_, i) => stalledClient(protocols.length + i));

const results = await Promise.all([...protocols.map(runClient), ...(args.refusedCheck ? [refusedCheck()] : [])]);
for (const ws of stalled) ws.terminate();
process.exit(results.every(Boolean) && !failed ? 0 : 1);
