#!/usr/bin/env bash
# ARAIM availability, a sweep in one run file (issue 36, docs/AVAILABILITY.md
# "Sweeps"): runs docs/runs/availability_sweep_europe.toml (33 scenarios,
# 35 users x 288 epochs each, a few CPU seconds), writes its outputs to
# docs/availability/sweep/ and its coverage table between the markers
# <!-- BEGIN generated: availability-sweep --> and <!-- END ... --> of
# docs/AVAILABILITY.md.
#   bash scripts/availability_sweep.sh           # rewrite
#   bash scripts/availability_sweep.sh --check   # compare with the committed files; exit 1 on a difference
# scripts/doc_tables.sh calls it (in its --check mode with --check).
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=write
case ${1:-} in
  --check) MODE=check ;;
  "") ;;
  *) echo "usage: $0 [--check]" >&2; exit 2 ;;
esac
cargo build --release -q -p raim-tool
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
./target/release/raim availability --run docs/runs/availability_sweep_europe.toml \
  --out "$TMP/sweep" --level 0.99 2> "$TMP/log" || { cat "$TMP/log" >&2; exit 1; }
cp docs/AVAILABILITY.md "$TMP/AVAILABILITY.md"
name="availability-sweep"
grep -q "<!-- BEGIN generated: $name -->" "$TMP/AVAILABILITY.md" || { echo "docs/AVAILABILITY.md: no marker $name" >&2; exit 1; }
awk -v b="<!-- BEGIN generated: $name -->" -v e="<!-- END generated: $name -->" -v f="$TMP/sweep/sweep_europe.sweep.md" '
  index($0, b) == 1 { print; while ((getline l < f) > 0) print l; skip = 1; next }
  index($0, e) == 1 { skip = 0 }
  !skip { print }' docs/AVAILABILITY.md > "$TMP/AVAILABILITY.md"
if [ $MODE = check ]; then
  status=0
  diff -ru docs/availability/sweep "$TMP/sweep" || status=1
  diff -u docs/AVAILABILITY.md "$TMP/AVAILABILITY.md" || status=1
  [ $status = 0 ] || echo "docs/availability/sweep or its table in docs/AVAILABILITY.md differ from what the code produces now (bash scripts/availability_sweep.sh)" >&2
  exit $status
fi
rm -rf docs/availability/sweep
cp -r "$TMP/sweep" docs/availability/sweep
cp "$TMP/AVAILABILITY.md" docs/AVAILABILITY.md
echo "rewrote docs/availability/sweep/ and the availability-sweep table of docs/AVAILABILITY.md"
