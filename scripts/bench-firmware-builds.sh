#!/usr/bin/env bash
# The firmware builds of scripts/test.sh from scratch, timed two ways
# (issue 37): each configuration in its own target directory (as test.sh
# built them before) and all four in one shared directory (as it builds them
# now). Usage: bash scripts/bench-firmware-builds.sh [SCRATCH_DIR]; the
# scratch directory (default /tmp/raim-fw-bench) is removed first. Wall
# times depend on the machine's load: give the load average with them
# (BENCHMARKS.md "Test suite: firmware builds").
set -euo pipefail
cd "$(dirname "$0")/../firmware"
dir=${1:-/tmp/raim-fw-bench}
rm -rf "$dir"
mkdir -p "$dir"
configs=(
    "default:"
    "stm32f4-hw:--no-default-features --features board-stm32f4"
    "stm32f4-netduinoplus2:--no-default-features --features board-stm32f4,qemu-netduinoplus2"
    "snapshot:--no-default-features --features board-qemu"
)
build() { # LABEL TARGET_DIR FEATURE_ARGS...
    local label=$1 target=$2 start
    shift 2
    start=${EPOCHREALTIME/./}
    # shellcheck disable=SC2068
    cargo build --release --quiet $@ --target-dir "$target"
    printf '%8.1f s  %s\n' "$(( (${EPOCHREALTIME/./} - start) / 100000 ))e-1" "$label"
}
echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== each configuration in its own target directory"
start=${EPOCHREALTIME/./}
for c in "${configs[@]}"; do
    build "${c%%:*}" "$dir/separate-${c%%:*}" ${c#*:}
done
printf '%8.1f s  total\n' "$(( (${EPOCHREALTIME/./} - start) / 100000 ))e-1"
echo "== one shared target directory"
start=${EPOCHREALTIME/./}
for c in "${configs[@]}"; do
    build "${c%%:*}" "$dir/shared" ${c#*:}
done
printf '%8.1f s  total\n' "$(( (${EPOCHREALTIME/./} - start) / 100000 ))e-1"
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
rm -rf "$dir"
