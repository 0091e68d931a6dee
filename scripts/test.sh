#!/usr/bin/env bash
# Second README command: installs dependencies, builds, and runs the whole test suite
# (unit, physics, CLI and example tests) with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
cd build
ctest --output-on-failure -j "${COHDEM_TEST_JOBS:-2}" --timeout 600
