// SPDX-License-Identifier: BSD-3-Clause
// Reads a ROS 1 bag with Foxglove's @foxglove/rosbag (what Foxglove does when it opens a .bag) and
// decodes every message with the connection's own message definition.
import { Bag } from "@foxglove/rosbag";
import { FileReader } from "@foxglove/rosbag/node.js";
import Bzip2 from "@foxglove/wasm-bz2";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg-serialization";

const bzip2 = await Bzip2.init();
const decompress = { bz2: (buffer, size) => bzip2.decompress(buffer, size, { small: false }) };
const bag = new Bag(new FileReader(process.argv[2]), { decompress });
await bag.open();
const readers = new Map();
for (const c of bag.connections.values()) readers.set(c.topic, new MessageReader(parse(c.messageDefinition)));
const counts = {};
const last = {};
await bag.readMessages({ decompress, noParse: true, topics: [...new Set([...bag.connections.values()].map((c) => c.topic))] }, (result) => {
  const msg = readers.get(result.topic).readMessage(result.data);
  counts[result.topic] = (counts[result.topic] ?? 0) + 1;
  last[result.topic] = msg;
});
console.log(JSON.stringify(counts));
console.log("/scan", JSON.stringify({ n: last["/scan"]?.ranges.length, amin: last["/scan"]?.angle_min, seq: last["/scan"]?.header.seq }));
console.log("/odom", JSON.stringify(last["/odom"]?.pose.pose.position));
console.log("/tf_static", JSON.stringify(last["/tf_static"]?.transforms[0]));
