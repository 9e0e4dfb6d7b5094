#!/usr/bin/env bash
# Installs terracut's Debian 12 build and run dependencies, only those missing
# (idempotent: a second run installs nothing and does not touch the network).
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  libpng-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libeigen3-dev libbullet-dev libasio-dev libenet-dev libzstd-dev libsodium-dev
  libglfw3-dev libepoxy-dev libimgui-dev
  libgl1-mesa-dri libegl-mesa0 libegl-dev xvfb xauth
  python3 python3-numpy python3-matplotlib gnuplot-nox
  pybind11-dev python3-dev python3-pytest python3-scipy python3-distributed python3-dask
  clang libclang-rt-14-dev
  liggghts
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
