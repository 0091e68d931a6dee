#!/usr/bin/env bash
# First README command: installs dependencies, builds, and runs the main job on the
# embedded default case. Extra arguments go to `cohdem run` (e.g. --set simulation.duration=0.05).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
exec ./build/cohdem run "$@"
