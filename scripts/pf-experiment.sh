#!/usr/bin/env bash
# Seed 004's experiment in shape on our data (docs/PF.md "Verification"):
# EKF, PF and GA-PF (100 and 300 particles) in the main + auxiliary FDI
# structure, each at the threshold of the calibrated table
# (crates/raim-core/src/pf/threshold_table.rs, made by `raim pf-table` on
# simulated nominal data, never on these files) for the allocated per-epoch
# Pfa; over SEEDS filter seeds with the fault onset spread uniformly over
# SPREAD seconds: false alarms against the allocation's binomial 99 % bound,
# detection probability, delay median / p95, wrong isolations, RMSE mean and
# 2.5-97.5 % range, N_eff before / after the GA step.
# Outputs docs/pf/verify_*.md (committed). Long mode (default, SEEDS=20):
# about 20 min of CPU; SEEDS=3 for a quick look.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p raim-tool
RAIM=./target/release/raim
D=../shared/data
OUT=docs/pf
SEEDS=${SEEDS:-20}
PFA=${PFA:-0.001}
mkdir -p $OUT

table() { # file, title, spread_s, then replay args
  local file=$1 title=$2 spread=$3; shift 3
  {
    echo "## $title"
    echo
    echo '```'
    echo "raim replay $* --pf <filter> --particles <N> --pf-pfa $PFA --pf-seeds $SEEDS --pf-onset-spread-s $spread --quiet"
    echo '```'
    echo
    local first=1
    for f in "ekf 100" "pf 100" "pf 300" "gapf 100" "gapf 300"; do
      read -r k n <<<"$f"
      out=$("$RAIM" replay "$@" --pf "$k" --particles "$n" --pf-pfa $PFA \
        --pf-seeds "$SEEDS" --pf-onset-spread-s "$spread" --quiet 2>&1 || true)
      if [ $first = 1 ]; then echo "$out" | grep '^| filter' ; echo "$out" | grep '^| ---'; first=0; fi
      echo "$out" | grep '^| [A-Z]' || echo "| $k | $n | error: $(echo "$out" | tail -1) |"
    done
    echo
  } >> "$OUT/$file"
}

GEOP=(--obs $D/GEOP092I.24o.gz --nav $D/CORD00ARG_R_20240920000_01D_MN.rnx.gz --systems GE)
S0759=(--obs $D/07590920.05o --nav $D/07590920.05n --systems G --mask-deg 15
  --pf-sigma-m 3 --pf-q-pos 0.1 --pf-q-clock 5 --pf-q-drift 0.5 --pf-window 5)

: > "$OUT/verify_geop.md"
table verify_geop.md "GEOP clean (phone_1hz profile, U = 10)" 0 "${GEOP[@]}"
for b in 5 20 50 100; do
  table verify_geop.md "GEOP, $b m step on G25, onset spread over epochs 100-400" 300 \
    "${GEOP[@]}" --fault step:G25:$b@+100
done
table verify_geop.md "GEOP, 1 m/s ramp on G25, onset spread over epochs 100-400" 300 \
  "${GEOP[@]}" --fault ramp:G25:1@+100

: > "$OUT/verify_0759.md"
table verify_0759.md "0759 clean (geodetic_30s profile, U = 5)" 0 "${S0759[@]}"
for b in 20 50 100; do
  table verify_0759.md "0759, $b m step on G24, onset spread over epochs 30-90" 1800 \
    "${S0759[@]}" --fault step:G24:$b@+900
done
echo "done: $OUT/verify_geop.md $OUT/verify_0759.md"
