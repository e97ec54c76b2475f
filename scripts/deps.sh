#!/usr/bin/env bash
# Installs, with apt-get, the Debian 12 packages polyexplore needs that are not
# there yet. Sourced by demo.sh, test.sh and bench.sh; safe to run again.
set -euo pipefail
PEX_DEBS=(
  build-essential cmake pkg-config
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev default-jdk-headless
  libeigen3-dev libboost-dev libspdlog-dev libfmt-dev libpolyclipping-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libtomlplusplus-dev libcli11-dev libsystemd-dev
  libcairo2-dev          # pex-render-map, pex-make-world: SVG and compressed, antialiased PNG
  iproute2 util-linux procps
  nftables libfaketime   # fault tests: LCM datagrams dropped, the wall clock stepped
  dpkg-dev file          # scripts/package.sh: cpack runs dpkg-shlibdeps (and file) for Depends
  strace                 # tests/systemd/sandbox_syscalls.sh: the units' syscall filters against the set
  systemd                # systemd-analyze: the units verified and scored in the tests
  libcpp-httplib-dev nlohmann-json3-dev  # pex-viewer: its HTTP server (and the tests' client), JSON
  chromium chromium-driver               # the viewer's browser tests: headless Chromium through WebDriver
  socat                  # scripts/demo.sh: the viewer's page from the demo's network namespace to this computer's loopback
  curl                   # tests/systemd/sandbox_syscalls.sh: pex-viewer's page fetched under strace
  default-jre libjchart2d-java  # pex-spy: lcm-spy's Swing GUI and its message view's plots (jchart2d)
  xvfb xdotool xclip imagemagick  # tests/spy: an X server, clicks and keys, the clipboard, screenshots
  systemd-container debootstrap openssh-client  # tests/systemd/nspawn_*.sh: the package booted under systemd in a Debian 12 root
)
# scripts/fuzz.sh only: clang and libFuzzer with its sanitizer runtimes.
if [ "${PEX_DEPS_FUZZ:-0}" = 1 ]; then
  PEX_DEBS+=(clang-14 libclang-rt-14-dev)
fi
missing=()
for p in "${PEX_DEBS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "deps: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
