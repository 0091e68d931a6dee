# Sourced by the validation scripts: the binary, the output root, timing.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=${COHDEM_BIN:-$root/build/cohdem}
out=${COHDEM_VALIDATE_OUT:-$root/out/validate}
mkdir -p "$out"
[ -x "$bin" ] || { echo "build first: cmake -S . -B build -G Ninja && ninja -C build (or set COHDEM_BIN)"; exit 2; }
timed() {  # label, command...: runs it, logs to $out/label.log, prints the wall time
  local label=$1; shift
  local t0=$(date +%s)
  echo "== $label: $*"
  "$@" > "$out/$label.log" 2>&1 || { echo "FAILED ($label), see $out/$label.log"; tail -5 "$out/$label.log"; exit 3; }
  echo "   $(( $(date +%s) - t0 )) s wall time; $(tail -1 "$out/$label.log")"
}
