#!/usr/bin/env bash
# Installs what deformlab needs from Debian (only what is missing), then configures and
# builds it with the CMake preset given as $1 (default: "default").
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-default}

packages=(cmake g++ make pkg-config git libeigen3-dev libgtest-dev libcli11-dev nlohmann-json3-dev
          libomp-dev libglew-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libstb-dev libvulkan-dev
          libassimp-dev libgmsh-dev libglfw3-dev libimgui-dev xvfb xauth ffmpeg)
[ "$preset" = fuzz ] && packages+=(clang libclang-rt-14-dev)  # libFuzzer
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# nvcc, where the CUDA toolkit is installed but not on PATH.
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then
  export PATH=/usr/local/cuda/bin:$PATH
fi

cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset"
