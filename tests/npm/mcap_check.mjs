// mcap_check.mjs: reads an MCAP file with readers others wrote (@mcap/core, @foxglove/*), the way
// Foxglove and Lichtblick do, so that the tests check shapeform's files against them.
//
// Usage: node tests/npm/mcap_check.mjs FILE [--decode]
//   A complete file (footer with a summary) is read with McapIndexedReader; a file without one (a
//   recording killed hard) with McapStreamReader, record by record, the way a reader recovers it: every
//   complete chunk, the record cut short at the end dropped. Chunks are decompressed with
//   @foxglove/wasm-zstd and @foxglove/wasm-lz4, CRCs checked. Every schema is parsed (omgidl with
//   @foxglove/omgidl-parser, jsonschema with JSON.parse).
//   Without --decode: one JSON object on stdout: {mode: "indexed"|"stream", schemas, channels,
//     messages, per_topic: {topic: count}, start_time, end_time, truncated_bytes}.
//   With --decode: one JSON line per message in log-time order (stable), {topic, log_time, message}
//     (log_time a decimal string; cdr decoded with @foxglove/omgidl-serialization's MessageReader,
//     json with JSON.parse), then nothing else.
//   Exit 1 with the reason on stderr on anything it cannot read; exit 2 on a bad command line.
//
// Where the packages come from: the test validators are installed by scripts/install_deps.sh into
// build/npm (never global). ESM ignores NODE_PATH, so this script loads them with createRequire from the
// folder named by the environment variable SHAPEFORM_NPM (a node_modules folder), by default
// build/npm/node_modules of the source tree this script is in. All of them ship CommonJS entry points.
import { createRequire } from "node:module";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const npm = path.resolve(process.env.SHAPEFORM_NPM || path.join(here, "..", "..", "build", "npm", "node_modules"));

function fail(message, code = 1) {
  process.stderr.write(`mcap_check: ${message}\n`);
  process.exit(code);
}

if (!fs.existsSync(path.join(npm, "@mcap", "core"))) {
  fail(`the npm validators are not in ${npm}: run scripts/install_deps.sh (or set SHAPEFORM_NPM)`);
}
const require = createRequire(path.join(npm, "noop.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { FileHandleReadable } = require("@mcap/nodejs");
const zstd = require("@foxglove/wasm-zstd");
const lz4 = require("@foxglove/wasm-lz4");
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

const args = process.argv.slice(2);
const decode = args.includes("--decode");
const files = args.filter((a) => a !== "--decode");
for (const a of files) if (a.startsWith("--")) fail(`unknown flag ${a} (usage: mcap_check.mjs FILE [--decode])`, 2);
if (files.length !== 1) fail("usage: mcap_check.mjs FILE [--decode]", 2);
const file = files[0];
if (!fs.existsSync(file)) fail(`${file}: no such file`, 1);

await zstd.isLoaded;
await (lz4.default ?? lz4).isLoaded;
const lz4Decompress = lz4.default ?? lz4;
const decompressHandlers = {
  zstd: (buffer, size) => zstd.decompress(buffer, Number(size)),
  lz4: (buffer, size) => lz4Decompress(buffer, Number(size)),
};

const MAGIC = Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]);
const bytes = fs.readFileSync(file);
if (bytes.length < 8 || !bytes.subarray(0, 8).equals(MAGIC)) fail(`${file}: not an MCAP file (no magic)`);
// A complete file ends with a footer and the magic; a killed one does not.
const hasFooter = bytes.length >= 8 + 29 + 8 && bytes.subarray(bytes.length - 8).equals(MAGIC) &&
  bytes[bytes.length - 8 - 29] === 0x02;

const schemas = new Map();
const channels = new Map();
const messages = [];
let mode, truncatedBytes = 0;

try {
  if (hasFooter) {
    mode = "indexed";
    const handle = await fs.promises.open(file, "r");
    try {
      const reader = await McapIndexedReader.Initialize({ readable: new FileHandleReadable(handle), decompressHandlers });
      for (const [id, s] of reader.schemasById) schemas.set(id, s);
      for (const [id, c] of reader.channelsById) channels.set(id, c);
      for await (const m of reader.readMessages({ validateCrcs: true })) messages.push(m);
      if (reader.statistics && reader.statistics.messageCount !== BigInt(messages.length)) {
        fail(`${file}: statistics say ${reader.statistics.messageCount} messages, read ${messages.length}`);
      }
    } finally {
      await handle.close();
    }
  } else {
    mode = "stream";
    const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
    reader.append(bytes);
    for (let r; (r = reader.nextRecord()) !== undefined;) {
      if (r.type === "Schema") schemas.set(r.id, r);
      else if (r.type === "Channel") channels.set(r.id, r);
      else if (r.type === "Message") messages.push(r);
    }
    truncatedBytes = reader.bytesRemaining();
  }
} catch (e) {
  fail(`${file}: ${e.message}`);
}

// Every schema parses.
const decoders = new Map();  // schema id -> (Uint8Array) => object
for (const [id, s] of schemas) {
  const text = new TextDecoder().decode(s.data);
  try {
    if (s.encoding === "omgidl") {
      const defs = parseIDL(text);
      const reader = new MessageReader(s.name, defs);
      decoders.set(id, (data) => reader.readMessage(data));
    } else if (s.encoding === "jsonschema") {
      JSON.parse(text);
    } else {
      fail(`${file}: schema ${id} (${s.name}): encoding ${s.encoding} is not checked by this script`);
    }
  } catch (e) {
    fail(`${file}: schema ${id} (${s.name}, ${s.encoding}) does not parse: ${e.message}`);
  }
}
for (const [id, c] of channels) {
  if (c.schemaId !== 0 && !schemas.has(c.schemaId)) fail(`${file}: channel ${id} (${c.topic}) names unknown schema ${c.schemaId}`);
}

// Log-time order, stable (the indexed reader already yields it; the stream reader yields file order).
const ordered = messages.map((m, i) => [m, i]).sort((a, b) =>
  a[0].logTime < b[0].logTime ? -1 : a[0].logTime > b[0].logTime ? 1 : a[1] - b[1]).map((x) => x[0]);

const replacer = (_k, v) => (typeof v === "bigint" ? v.toString() : v);
const out = [];
const perTopic = {};
for (const m of ordered) {
  const c = channels.get(m.channelId);
  if (!c) fail(`${file}: a message on channel ${m.channelId}, which no channel record defines`);
  perTopic[c.topic] = (perTopic[c.topic] ?? 0) + 1;
  if (!decode) continue;
  let message;
  try {
    if (c.messageEncoding === "cdr") {
      const d = decoders.get(c.schemaId);
      if (!d) fail(`${file}: channel ${c.topic}: cdr without an omgidl schema`);
      message = d(m.data);
    } else if (c.messageEncoding === "json") {
      message = JSON.parse(new TextDecoder().decode(m.data));
    } else {
      fail(`${file}: channel ${c.topic}: message encoding ${c.messageEncoding} is not checked by this script`);
    }
  } catch (e) {
    fail(`${file}: message on ${c.topic} at log_time ${m.logTime} does not decode: ${e.message}`);
  }
  out.push(JSON.stringify({ topic: c.topic, log_time: m.logTime.toString(), message }, replacer));
}
if (decode) {
  process.stdout.write(out.length ? out.join("\n") + "\n" : "");
} else {
  process.stdout.write(JSON.stringify({
    mode,
    schemas: schemas.size,
    channels: channels.size,
    messages: messages.length,
    per_topic: perTopic,
    start_time: ordered.length ? ordered[0].logTime.toString() : null,
    end_time: ordered.length ? ordered[ordered.length - 1].logTime.toString() : null,
    truncated_bytes: truncatedBytes,
  }) + "\n");
}
