#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Seed corpora for the fuzz targets: small valid inputs, from the heads of the real files in
# $SLAM2D_DATA (../shared/data) and from the simulator through the slam2d CLI of the release build
# ($SLAM2D_BIN). Whatever is missing is skipped: libFuzzer also starts from nothing.
#
# usage: fuzz/seed_corpus.sh CORPUS TMP
set -uo pipefail
out=$1
tmp=$2
here=$(cd "$(dirname "$0")" && pwd)
data=${SLAM2D_DATA:-$here/../../shared/data}
bin=${SLAM2D_BIN:-$here/../build/release/bin/slam2d}
mkdir -p "$tmp"
for t in carmen carmen_gz relations trajectory pose_graph_g2o pose_graph_toro map_yaml pgm png config ros1_bag mcap \
         rosbag2_db3 cdr ros1_message; do
  mkdir -p "$out/$t"
done

# Whole lines from the first N bytes of a stream.
head_lines() { head -c "$1" | sed '$d'; }

for log in intel aces fr079; do
  if [[ -f "$data/$log/$log.clf.gz" ]]; then
    zcat "$data/$log/$log.clf.gz" | head_lines 30000 >"$out/carmen/$log.clf"
    gzip -c "$out/carmen/$log.clf" >"$out/carmen_gz/$log.clf.gz"
  fi
  [[ -f "$data/$log/$log.relations" ]] && head -n 40 "$data/$log/$log.relations" >"$out/relations/$log.relations"
done
[[ -f "$data/posegraphs/vertigo/intel.g2o" ]] && head -n 400 "$data/posegraphs/vertigo/intel.g2o" >"$out/pose_graph_g2o/intel.g2o"
[[ -f "$data/posegraphs/hog-man/w10000.graph.gz" ]] && zcat "$data/posegraphs/hog-man/w10000.graph.gz" | head -n 400 \
    >"$out/pose_graph_toro/w10000.graph"
cp "$here"/../configs/*.yaml "$out/config/" 2>/dev/null

if [[ -x "$bin" ]]; then
  "$bin" simulate --quiet --duration 3 --seed 1 --out "$tmp/sim.clf" --truth "$tmp/truth.txt"
  cp "$tmp/sim.clf" "$out/carmen/sim.clf"
  cp "$tmp/truth.txt" "$out/trajectory/truth.txt"
  awk '!/^#/ {printf "%s %s %s 0 0 0 %.9f %.9f\n", $1, $2, $3, sin($4 / 2), cos($4 / 2)}' "$tmp/truth.txt" \
      >"$out/trajectory/truth.tum"
  "$bin" convert "$tmp/sim.clf" "$out/ros1_bag/sim.bag" --quiet >/dev/null 2>&1
  "$bin" convert "$tmp/sim.clf" "$out/mcap/sim.mcap" --quiet >/dev/null 2>&1
  "$bin" map "$tmp/sim.clf" --method odometry --resolution 0.25 --out "$tmp/map" --quiet >/dev/null 2>&1
  cp "$tmp/map/map.pgm" "$out/pgm/map.pgm" 2>/dev/null
  cp "$tmp/map/map.png" "$out/png/map.png" 2>/dev/null
  sed 's/image: .*/image: map.pgm/' "$tmp/map/map.yaml" >"$out/map_yaml/map.yaml" 2>/dev/null
fi
# A rosbag2 sqlite3 file with its tables and one topic (the storage plugin's schema).
/usr/bin/python3 - "$out/rosbag2_db3/bag_0.db3" <<'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.executescript("""
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL,
                    offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
INSERT INTO schema VALUES (3, 'humble');
INSERT INTO topics VALUES (1, '/scan', 'sensor_msgs/msg/LaserScan', 'cdr', '');
""")
db.commit()
PY
echo "seed_corpus: $(find "$out" -type f | wc -l) files in $out" >&2
