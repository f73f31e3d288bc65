#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reads files written by slam2d (convert, map --mcap, localize --mcap) the way Foxglove does:
# MCAP with the official MCAP TypeScript library (indexed reader, then a stream reader checking
# every CRC) and Foxglove's ros2msg parser and CDR reader; ROS 1 bags with @foxglove/rosbag and
# its ROS 1 message reader; every message decoded. Needs Node.js and the npm registry (packages
# pinned in package-lock.json, installed into node_modules/ here).
# Usage: tools/foxglove_check/run.sh FILE.mcap|FILE.bag...
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ -d "$here/node_modules" ] || (cd "$here" && npm ci --silent --no-audit --no-fund)
for file in "$@"; do
  echo "== $file"
  case "$file" in
    *.bag) node "$here/checkbag.mjs" "$file" ;;
    *) node "$here/check.mjs" "$file" ;;
  esac
done
