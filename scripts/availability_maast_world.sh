#!/usr/bin/env bash
# Our availability engine against the ADD v4.2 reference implementation
# (4datascience/ARAIM-Fault-Detection, a MAAST-derived ARAIM in Matlab)
# on EVERY user-epoch of the MAAST scenario (docs/runs/availability_maast_g24e24.toml:
# 10 deg world grid, 684 users x 288 epochs, detection only), run under
# GNU Octave (docs/AVAILABILITY.md "The reference on the whole world
# grid"). Not run by CI (no Octave there); the reference is not part of
# this repository. The 288-user-epoch diagnostic with more variants is
# scripts/availability_maast_compare.sh.
#
#   bash scripts/availability_maast_world.sh /path/to/ARAIM-Fault-Detection [WORK_DIR]
#
# 1. `dump_sky --by-latitude` writes every user-epoch as our engine
#    formed it (satellites in view, C_int, C_acc) and our outputs.
# 2. scripts/octave/availability_maast_world.m runs the reference on them,
#    variant by variant ($VARIANTS, default "published v3"; its header
#    says what each is), each in two niced Octave processes that take the
#    latitude bands from either end (a band already written is skipped,
#    so the two meet in the middle, and the command resumes a stopped
#    run). About 40-200 user-epochs/s per process, depending on the load:
#    197k user-epochs per variant.
# 3. scripts/availability_maast_world.py computes per user availability,
#    the 99.5th-percentile VPL and HPL and the coverage from each side's
#    PLs, and prints the comparison (Markdown).
set -euo pipefail
ref=${1:?usage: availability_maast_world.sh REF_CHECKOUT [WORK_DIR]}
work=${2:-target/availability-maast-world}
here=$(cd "$(dirname "$0")/.." && pwd)
lib=$(cd "$ref/araim_matlab/lib" && pwd)
command -v octave-cli >/dev/null || { echo "octave-cli not found (apt-get install octave)" >&2; exit 1; }
mkdir -p "$work/shadow"
work=$(cd "$work" && pwd)
cd "$here"
cargo run --release -q -p raim-availability --example dump_sky -- \
  docs/runs/availability_maast_g24e24.toml "$work" --by-latitude
printf 'function y = modnormcdf(x)\ny = normcdf(x);\nend\n' > "$work/shadow/modnormcdf.m"
run() { # VARIANT SHADOW LATS
  nice octave-cli --path "$here/scripts/octave" \
    --eval "availability_maast_world('$lib', '$work', '$1', '$2', $3)" 2>&1 \
    | grep --line-buffered -E '^[a-z0-9]+ lat ' | tee -a "$work/octave.log"
}
for v in ${VARIANTS:-published v3}; do
  shadow=""
  [ "$v" = v3 ] && shadow="$work/shadow"
  run "$v" "$shadow" "[-90:10:90]" &
  a=$!
  run "$v" "$shadow" "[90:-10:-90]" &
  b=$!
  wait "$a" "$b"
done
python3 scripts/availability_maast_world.py "$work"
