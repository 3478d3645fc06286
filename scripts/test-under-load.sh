#!/usr/bin/env bash
# The suite with a second build running beside it (issue 37: "passing with
# a second build running beside it"): `cargo build --release --workspace`
# into a separate target directory, cleaned and started again until the
# suite ends, while scripts/test.sh runs. Prints the suite's per-step
# table, the load averages seen, and how many background builds ran.
#
#   bash scripts/test-under-load.sh
set -euo pipefail
cd "$(dirname "$0")/.."
other=$(mktemp -d)
loads=$(mktemp)
(
    while true; do
        rm -rf "$other/target"
        cargo build --release --workspace --quiet --target-dir "$other/target" >/dev/null 2>&1 || true
        echo build >>"$loads"
    done
) &
builder=$!
(
    while true; do
        cut -d' ' -f1 /proc/loadavg >>"$loads"
        sleep 10
    done
) &
sampler=$!
cleanup() {
    kill "$builder" "$sampler" 2>/dev/null || true
    # cargo and its rustc processes name the other target directory.
    pkill -f "$other/target" 2>/dev/null || true
    rm -rf "$other"
}
trap cleanup EXIT
status=0
bash scripts/test.sh || status=$?
echo "== beside it: $(grep -c build "$loads") background build(s) completed; 1-minute load average min/median/max:" \
    "$(grep -v build "$loads" | sort -n | awk '{a[NR]=$1} END {print a[1] " / " a[int((NR+1)/2)] " / " a[NR]}')"
rm -f "$loads"
exit $status
