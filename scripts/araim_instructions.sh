#!/bin/bash
# x86 instructions per ARAIM epoch (BENCHMARKS.md, "ARAIM on the host"):
# callgrind's count at ITERS epochs minus the count at 0, / ITERS, for each
# case of crates/raim-core/examples/araim_count.rs (the FDE cases at 2).
#   cargo build --release -p raim-core --example araim_count
#   bash scripts/araim_instructions.sh [target/release/examples/araim_count]
set -euo pipefail
bin=${1:-target/release/examples/araim_count}
count() {
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$1" "$2" 2>&1 |
        sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
per_epoch() {
    local at zero
    at=$(count "$1" "$2")
    zero=$(count "$1" 0)
    echo "$1 $(((at - zero) / $2))"
}
for case in appendix_d sky20 sky30_pconst1e-8 sky30_pconst1e-4; do
    per_epoch "$case" 20
done
for case in sky30_pconst1e-8+fde sky30_pconst1e-8+fde2; do
    per_epoch "$case" 2
done
