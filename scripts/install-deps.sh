#!/usr/bin/env bash
# Installs every build and test dependency of vdbwrap from Debian's packages.
# Used by the README, .ci/run and docker/Dockerfile: keep it the only install path.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != "0" ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
PKGS=(
  build-essential cmake ninja-build ccache pkg-config git
  libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev zlib1g-dev
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc
  libgtest-dev libgmock-dev
  libcli11-dev nlohmann-json3-dev libyaml-cpp-dev
  python3 python3-grpcio python3-protobuf python3-yaml python3-venv python3-setuptools python3-wheel openssl
  clang libclang-rt-14-dev
  libjs-three chromium  # --html embeds three.js; its test renders the page in headless Chromium
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all packages present" >&2
fi
