#!/usr/bin/env bash
# A loaded host's scheduling, made repeatable (issue 37, docs/EVIDENCE.md
# "The suite under load"): runs one QEMU test and, while it runs, stops
# each QEMU process the test started (by its pid, SIGSTOP) for $STALL s
# every $PERIOD s, as a host that does not schedule QEMU for that long.
# Prints the test's result, how many stalls it took, and the load average.
#
#   STALL=0.8 PERIOD=0.1 bash scripts/qemu-stall.sh TEST_BINARY FILTER
#
# TEST_BINARY is a host-tests test executable (`cargo test --release -p
# host-tests --test qemu_link --no-run` prints it); FILTER selects the
# test. STALL=0 runs it without stalls. ICOUNT="shift=0,sleep=off" (any
# `-icount` argument) runs QEMU with `-icount $ICOUNT` appended, through a
# wrapper put first on PATH.
set -euo pipefail
bin=$1
filter=$2
stall=${STALL:-0.8}
period=${PERIOD:-0.1}
work=$(mktemp -d)
if [ -n "${ICOUNT:-}" ]; then
    mkdir "$work/bin"
    real=$(command -v qemu-system-arm)
    printf '#!/bin/sh\nexec %s "$@" -icount %s\n' "$real" "$ICOUNT" >"$work/bin/qemu-system-arm"
    chmod +x "$work/bin/qemu-system-arm"
    export PATH="$work/bin:$PATH"
fi
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$bin" "$filter" --nocapture >"$work/out" 2>&1 &
test_pid=$!
stalls=0
while kill -0 "$test_pid" 2>/dev/null; do
    if [ "$stall" != 0 ]; then
        for q in $(pgrep -P "$test_pid" -x qemu-system-arm || true); do
            kill -STOP "$q" 2>/dev/null || continue
            sleep "$stall"
            kill -CONT "$q" 2>/dev/null || true
            stalls=$((stalls + 1))
        done
    fi
    sleep "$period"
done
rc=0
wait "$test_pid" || rc=$?
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "exit $rc, $stalls stalls of $stall s"
grep -E "frames/s|panicked|Undecodable|test result" "$work/out" || true
rm -rf "$work"
exit "$rc"
