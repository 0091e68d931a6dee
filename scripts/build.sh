#!/usr/bin/env bash
# Configures and builds cohdem in ./build (Release). Used by run-main.sh and test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${COHDEM_JOBS:-$(nproc)}
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j "$JOBS" >> build.log 2>&1 || { tail -60 build.log; exit 1; }
echo "build: ok (log in build.log)"
