#!/usr/bin/env bash
# The installed package as another project sees it: `cmake --install` the build tree into a
# fresh prefix, build examples/consumer against that prefix alone (find_package(slam2d)), run its
# two programs (match two scans; graph SLAM over a simulated log from the installed tool) and
# check what they print and write.
#   consumer_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(realpath "$1")
source=$(realpath "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/slam2d/methods/matcher_registry.hpp"
test -f "$work/prefix/lib/cmake/slam2d/slam2dConfig.cmake" || test -f "$work/prefix/lib/x86_64-linux-gnu/cmake/slam2d/slam2dConfig.cmake"
cmake -S "$source/examples/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF >/dev/null
# The consumer must read the installed headers, never the source tree's.
if grep -rq -- "$source/src" "$work/consumer/CMakeFiles" 2>/dev/null; then
  echo "consumer_test: the consumer build refers to the source tree $source/src" >&2
  exit 1
fi
cmake --build "$work/consumer" -j2 >/dev/null

"$work/consumer/match_scans" | tee "$work/match.txt"
grep -q "^recovered$" "$work/match.txt"

"$work/prefix/bin/slam2d" simulate --out "$work/office.clf" --duration 40 --quiet
"$work/consumer/map_log" "$work/office.clf" "$work/trajectory.txt"
scans=$(grep -c "^FLASER" "$work/office.clf")
poses=$(grep -vc "^#" "$work/trajectory.txt")
if [[ "$scans" -lt 100 || "$poses" -ne "$scans" ]]; then
  echo "consumer_test: $poses poses for $scans scans" >&2
  exit 1
fi
echo "consumer_test: the installed package built the consumer; $poses poses for $scans scans"
