#!/usr/bin/env bash
# Our availability engine against the ADD v4.2 reference implementation
# (4datascience/ARAIM-Fault-Detection, a MAAST-derived ARAIM in Matlab),
# run under GNU Octave on the same user-epochs (docs/AVAILABILITY.md
# "Against the ADD v4.2 reference implementation"). Not run by CI (no
# Octave there); the reference is not part of this repository.
#
#   bash scripts/availability_maast_compare.sh /path/to/ARAIM-Fault-Detection [WORK_DIR]
#
# 1. `dump_sky` writes every user-epoch of docs/runs/availability_maast_compare.toml
#    (G24 + E24, the MAAST ISM, 12 users x 24 epochs): the satellites in
#    view with C_int, C_acc as raim-core formed them, and our VPL, HPL, EMT.
# 2. scripts/octave/availability_maast_compare.m runs the reference's
#    araim_baseline_v4_2 on them (five variants, its header says which).
# 3. The same with the reference's modnormcdf (which rounds Phi above 0.5
#    up to 1) replaced by the plain normal distribution function.
# 4. scripts/availability_maast_compare.py tabulates both.
set -euo pipefail
ref=${1:?usage: availability_maast_compare.sh REF_CHECKOUT [WORK_DIR]}
work=${2:-target/availability-maast-compare}
here=$(cd "$(dirname "$0")/.." && pwd)
lib=$(cd "$ref/araim_matlab/lib" && pwd)
command -v octave-cli >/dev/null || { echo "octave-cli not found (apt-get install octave)" >&2; exit 1; }
mkdir -p "$work/plain_cdf" "$work/shadow"
work=$(cd "$work" && pwd)
cd "$here"
cargo run --release -q -p raim-availability --example dump_sky -- docs/runs/availability_maast_compare.toml "$work"
cp "$work/sky.csv" "$work/ours.csv" "$work/plain_cdf/"
printf 'function y = modnormcdf(x)\ny = normcdf(x);\nend\n' > "$work/shadow/modnormcdf.m"
run() {
  (cd "$work" && octave-cli --path "$here/scripts/octave" \
    --eval "availability_maast_compare('$lib', '$1', '$2')" 2>&1 | grep -E '^(ADD|App|[0-9]+ user-epochs)')
}
echo "## The reference as published"
run "$work" ""
python3 scripts/availability_maast_compare.py "$work"
echo
echo "## The reference with modnormcdf = normcdf"
run "$work/plain_cdf" "$work/shadow"
python3 scripts/availability_maast_compare.py "$work/plain_cdf"
