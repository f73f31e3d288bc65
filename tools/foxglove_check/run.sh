#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reads MCAP files written by slam2d (convert, map --mcap, localize --mcap) the way Foxglove does:
# the official MCAP TypeScript library (indexed reader, then a stream reader checking every CRC)
# and Foxglove's ros2msg parser and CDR reader, decoding every message. Needs Node.js and the npm
# registry (packages pinned in package-lock.json, installed into node_modules/ here).
# Usage: tools/foxglove_check/run.sh FILE.mcap...
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ -d "$here/node_modules" ] || (cd "$here" && npm ci --silent --no-audit --no-fund)
for file in "$@"; do
  echo "== $file"
  node "$here/check.mjs" "$file"
done
