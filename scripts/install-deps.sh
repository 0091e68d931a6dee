#!/usr/bin/env bash
# Installs every Debian 12 package cohdem needs to build, test, run and plot.
# Idempotent: packages already present are skipped quickly.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build pkg-config   # compiler and build system
  libtomlplusplus-dev   # case files (TOML, with line numbers for error messages)
  libcli11-dev          # command-line interface
  libfmt-dev libspdlog-dev   # formatting and logging
  nlohmann-json3-dev    # JSON summaries
  libgtest-dev libgmock-dev  # unit and physics tests
  libbenchmark-dev      # micro-benchmarks in bench/
  gnuplot-nox           # PNG plots of results
  binutils              # objdump: the test that the contact laws are inlined into the force loops
  valgrind              # callgrind: bench/instructions.py counts instructions per particle-step
  python3               # 3.11 (tomllib): the CLI tests' summary checks, bench/ and scripts/validate/ scripts
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "install-deps: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
