#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The installed package as another project sees it: `cmake --install` the build tree into a
# fresh prefix, build examples/consumer against that prefix alone (find_package(slam2d)), run its
# two programs (match two scans; graph SLAM over a simulated log from the installed tool) and
# check what they print and write.
#   consumer_test.sh BUILD_DIR SOURCE_DIR [SANITIZERS]
# SANITIZERS: the build's SLAM2D_SANITIZE (its static libraries need the runtime in the consumer).
set -euo pipefail
build=$(realpath "$1")
source=$(realpath "$2")
sanitize_flags=${3:+-fsanitize=$3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/slam2d/methods/matcher_registry.hpp"
test -f "$work/prefix/lib/cmake/slam2d/slam2dConfig.cmake" || test -f "$work/prefix/lib/x86_64-linux-gnu/cmake/slam2d/slam2dConfig.cmake"
# Public headers only: the internals under detail/ stay in the source tree, and every installed
# header compiles from the installed tree alone (one translation unit including them all).
if find "$work/prefix/include/slam2d" -type d -name detail | grep -q .; then
  echo "consumer_test: a detail/ folder was installed" >&2
  exit 1
fi
(cd "$work/prefix/include" && find slam2d -name '*.hpp' | sort | sed 's/.*/#include "&"/') > "$work/all_headers.cpp"
headers=$(grep -c include "$work/all_headers.cpp")
c++ -std=c++20 -fsyntax-only -I"$work/prefix/include" -I/usr/include/eigen3 "$work/all_headers.cpp"
cmake -S "$source/examples/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  -DCMAKE_CXX_FLAGS="$sanitize_flags" -DCMAKE_EXE_LINKER_FLAGS="$sanitize_flags" >/dev/null
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
echo "consumer_test: $headers public headers compile from the installed tree; the installed package built the consumer; $poses poses for $scans scans"
