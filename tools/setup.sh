#!/usr/bin/env bash
# Installs what hybrid-rt needs on a Debian 12 machine, idempotently: every step first checks
# whether its work is already done and says so. Safe to run any number of times.
#
# Why each piece is here:
# - Mesa >= 24.1 from bookworm-backports: its lavapipe exposes VK_KHR_acceleration_structure and
#   VK_KHR_ray_query on the CPU; Debian 12's own Mesa 22 does not (the compute backend still works).
# - vulkan-validationlayers: tests run with core + synchronization validation.
# - cmake, ninja, python3, git, g++: the shaderc crate builds libshaderc from source, because
#   Debian's libshaderc-dev does not link (see PLATFORM-NOTES).
set -euo pipefail

say() { printf '[setup] %s\n' "$*"; }

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    say "not root and no sudo: install the packages listed in tools/setup.sh by hand"; exit 1
  fi
fi

if ! grep -qs '^ID=debian' /etc/os-release || ! grep -qs 'VERSION_CODENAME=bookworm' /etc/os-release; then
  say "this script targets Debian 12 (bookworm); on other systems install: a Vulkan loader, Mesa lavapipe >= 24.1,"
  say "the Khronos validation layers, cmake, ninja, python3, git and a C++ compiler"
  exit 0
fi

APT_LOG=/tmp/hybrid-rt-setup-apt.log
APT_UPDATED=0
apt_install() {
  # apt's own chatter goes to a log; on failure the log's tail is shown.
  if ! DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q "$@" >>"$APT_LOG" 2>&1; then
    tail -n 20 "$APT_LOG"; say "apt-get install $* failed (full log: $APT_LOG)"; exit 1
  fi
}
apt_update() {
  if [ "$APT_UPDATED" -eq 0 ]; then
    say "apt-get update"
    $SUDO apt-get update -qq >>"$APT_LOG" 2>&1 || { tail -n 20 "$APT_LOG"; say "apt-get update failed"; exit 1; }
    APT_UPDATED=1
  fi
}

# 1. bookworm-backports source
if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
  say "adding the bookworm-backports apt source"
  printf 'Types: deb\nURIs: http://deb.debian.org/debian\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null
  APT_UPDATED=0
  apt_update
else
  say "bookworm-backports source: present"
fi

# 2. Mesa lavapipe >= 24.1 from backports
mesa_ver=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
if [ -z "$mesa_ver" ] || dpkg --compare-versions "$mesa_ver" lt 24.1; then
  apt_update
  say "installing mesa-vulkan-drivers from bookworm-backports (have: ${mesa_ver:-none})"
  apt_install -t bookworm-backports mesa-vulkan-drivers
  mesa_ver=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers)
fi
say "mesa-vulkan-drivers $mesa_ver"

# 3. the loader, validation layers and build tools
PKGS=(libvulkan1 vulkan-tools vulkan-validationlayers build-essential pkg-config cmake ninja-build python3 git)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  apt_update
  say "installing: ${missing[*]}"
  apt_install "${missing[@]}"
else
  say "build tools, Vulkan loader and validation layers: present"
fi

# 4. the viewer's window test (tests/viewer.rs): a virtual X server, ImageMagick (a fallback
# screenshot) and the X11 libraries winit loads at run time
XPKGS=(xvfb imagemagick libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6)
missing=()
for p in "${XPKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  apt_update
  say "installing: ${missing[*]}"
  apt_install "${missing[@]}"
else
  say "Xvfb, ImageMagick and the X11 libraries: present"
fi

# 5. a quick check that the loader sees lavapipe
if command -v vulkaninfo >/dev/null 2>&1; then
  dev=$(vulkaninfo --summary 2>/dev/null | grep -m1 'deviceName' | sed 's/.*= //' || true)
  say "Vulkan device: ${dev:-none found}"
  if vulkaninfo 2>/dev/null | grep VK_KHR_ray_query >/dev/null; then
    say "ray query: available (the rayquery backend can be tested)"
  else
    say "ray query: not available (the compute backend will be used)"
  fi
fi
say "done"
