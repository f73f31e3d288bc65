#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs every fuzz target (issue 25; docs/reliability.md) for SECONDS each over its corpus, seeded
# from ../shared/data and the simulator (fuzz/seed_corpus.sh). A crash, a sanitizer report, an
# escaped exception, a leak or an allocation over the limits fails the run; the input is kept in
# BUILD/fuzz-artifacts/ to be added to tests/fixtures/fuzz/TARGET/ as a regression test.
#
# usage: fuzz/run.sh BUILD SECONDS [TARGET...]
#   prints one line per target (executions, executions per second, corpus size, crashes) and
#   writes BUILD/fuzz-summary.json.
set -uo pipefail
build=$1
seconds=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(carmen carmen_gz relations trajectory pose_graph_g2o pose_graph_toro map_yaml pgm png
                                     config ros1_bag mcap rosbag2_db3 cdr ros1_message)
corpus="$build/fuzz-corpus"
artifacts="$build/fuzz-artifacts"
mkdir -p "$artifacts"
[[ -d "$corpus" ]] || bash "$here/seed_corpus.sh" "$corpus" "$build/fuzz-seed-tmp"

dict_of() {
  case $1 in
    carmen | carmen_gz) echo "$here/dict/carmen.dict" ;;
    relations | trajectory) echo "$here/dict/relations.dict" ;;
    pose_graph_*) echo "$here/dict/pose_graph.dict" ;;
    map_yaml | config) echo "$here/dict/yaml.dict" ;;
  esac
}

failed=0
summary="["
for name in "${targets[@]}"; do
  mkdir -p "$corpus/$name"
  dict=$(dict_of "$name")
  log="$build/fuzz-$name.log"
  # Limits: 2 GiB of memory and 512 MiB in one allocation (a hostile size must be an error long
  # before that), 10 s per input.
  "$build/fuzz/fuzz_$name" "$corpus/$name" ${dict:+-dict="$dict"} -max_total_time="$seconds" -rss_limit_mb=2048 \
      -malloc_limit_mb=512 -timeout=10 -max_len=65536 -print_final_stats=1 -artifact_prefix="$artifacts/$name-" \
      >"$log" 2>&1
  rc=$?
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  rate=$(grep -oE 'stat::average_exec_per_sec: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  size=$(find "$corpus/$name" -type f | wc -l)
  crashes=$(find "$artifacts" -name "$name-*" -type f | wc -l)
  status=ok
  if [[ $rc -ne 0 ]]; then status="FAILED (exit $rc, see $log)"; failed=1; fi
  printf '%-16s %10s runs %7s/s  corpus %5s  artifacts %s  %s\n' "$name" "${runs:-0}" "${rate:-0}" "$size" "$crashes" "$status"
  summary+="{\"target\":\"$name\",\"seconds\":$seconds,\"runs\":${runs:-0},\"runs_per_s\":${rate:-0},\"corpus\":$size,\"artifacts\":$crashes,\"exit\":$rc},"
done
echo "${summary%,}]" > "$build/fuzz-summary.json.tmp" && mv "$build/fuzz-summary.json.tmp" "$build/fuzz-summary.json"
exit $failed
