#!/usr/bin/env bash
# Installs the Debian 12 packages hemo needs, only when something is missing.
# Used by `make run` and `make test`; safe to run again (a second run does nothing).
set -euo pipefail

packages=(
  g++ cmake ninja-build make pkg-config
  libvulkan-dev            # Vulkan loader and headers
  vulkan-validationlayers  # VK_LAYER_KHRONOS_validation (every test runs with it)
  mesa-vulkan-drivers      # lavapipe: Vulkan on the CPU when there is no GPU
  glslang-tools spirv-tools
  libglm-dev nlohmann-json3-dev libglfw3-dev libgtest-dev
  libpng-dev               # PNG frames (render/)
  xvfb xauth               # a virtual X server: the windowed viewer runs in CI
  libimgui-dev             # Dear ImGui with its GLFW and Vulkan backends: the viewer's panel
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "hemo: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "hemo: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
