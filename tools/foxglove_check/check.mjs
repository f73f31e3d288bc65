// SPDX-License-Identifier: BSD-3-Clause
// Reads an MCAP with the official @mcap/core indexed reader and decodes every message with
// Foxglove's ros2msg parser + CDR deserializer: what Foxglove Studio does when it opens a file.
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { decompress as zstd } from "fzstd";
import lz4 from "lz4js";
import { open } from "node:fs/promises";
import { readFileSync } from "node:fs";

const path = process.argv[2];
const decompressHandlers = {
  zstd: (data, size) => zstd(data, new Uint8Array(Number(size))),
  lz4: (data, size) => Uint8Array.from(lz4.decompress(data, Number(size))),
};
const handle = await open(path, "r");
const readable = {
  size: async () => BigInt((await handle.stat()).size),
  read: async (offset, length) => {
    const buf = new Uint8Array(Number(length));
    await handle.read(buf, 0, Number(length), Number(offset));
    return buf;
  },
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const readers = new Map();
for (const [id, schema] of reader.schemasById) {
  const defs = parse(new TextDecoder().decode(schema.data), { ros2: true });
  readers.set(id, new MessageReader(defs));
}
const counts = {};
let last = {};
for await (const m of reader.readMessages()) {
  const channel = reader.channelsById.get(m.channelId);
  const msg = readers.get(channel.schemaId).readMessage(m.data);
  counts[channel.topic] = (counts[channel.topic] ?? 0) + 1;
  last[channel.topic] = msg;
}
console.log(JSON.stringify(counts));
const summarize = (topic, f) => last[topic] && console.log(topic, JSON.stringify(f(last[topic])));
summarize("/map", (m) => ({ frame: m.header.frame_id, w: m.info.width, h: m.info.height, res: m.info.resolution, n: m.data.length, origin: m.info.origin.position }));
summarize("/path", (m) => ({ n: m.poses.length, last: m.poses.at(-1).pose.position }));
summarize("/scan_map", (m) => ({ frame: m.header.frame_id, width: m.width, fields: m.fields.map((f) => f.name), bytes: m.data.length }));
summarize("/scan", (m) => ({ n: m.ranges.length, amin: m.angle_min, inc: m.angle_increment }));
summarize("/odom", (m) => ({ child: m.child_frame_id, p: m.pose.pose.position }));
summarize("/tf_static", (m) => m.transforms[0]);
// the stream reader (no index) too: every record, CRCs checked
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(readFileSync(path));
let records = 0;
for (let r; (r = stream.nextRecord()); ) records++;
console.log("stream records", records, "done", stream.done());
