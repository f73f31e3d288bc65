#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs slam2d's build and test dependencies from Debian 12 packages.
# Idempotent: silent and quick when everything is already present.
set -euo pipefail

packages=(
  build-essential cmake make pkg-config
  libeigen3-dev libnanoflann-dev libsuitesparse-dev libyaml-cpp-dev
  libcli11-dev libfmt-dev zlib1g-dev libbz2-dev liblz4-dev libpng-dev
  libgtest-dev libgmock-dev libbenchmark-dev libtbb-dev libzstd-dev libsqlite3-dev
  clang libclang-rt-14-dev
  python3 python3-dev python3-pybind11 python3-numpy python3-pytest python3-yaml python3-distributed python3-matplotlib
  chromium
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
[[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
