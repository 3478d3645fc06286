#!/usr/bin/env bash
# The committed outputs of docs/AVAILABILITY.md's single runs (issue 36): the
# summaries and per-user CSVs under docs/availability/ of the six run files
# below, each made by the command the doc gives
#   raim availability --run docs/runs/availability_NAME.toml --out docs/availability --level 0.99 --maps
# (the MAAST scenario with exclusion takes about 15 s of CPU, the rest a few).
#   bash scripts/availability_outputs.sh           # rewrite (maps included)
#   bash scripts/availability_outputs.sh --check   # compare the JSON and CSV with the committed ones; exit 1 on a difference
# scripts/doc_tables.sh calls it (in its --check mode with --check). The maps
# (PNG) are rewritten, not compared: they are drawn from the same numbers.
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
status=0
for name in esbc_nav maast_g24e24 maast_g24e24_fde maast_g24e24_galtable maast_g24e24_ed259a maast_g24e24_adjusted; do
  maps=()
  [ $MODE = write ] && maps=(--maps)
  ./target/release/raim availability --run "docs/runs/availability_$name.toml" \
    --out "$TMP" --level 0.99 "${maps[@]}" 2> "$TMP/log" || { cat "$TMP/log" >&2; exit 1; }
  for f in "$TMP"/availability_"$name".*; do
    b=$(basename "$f")
    if [ $MODE = check ]; then
      case $b in *.json|*.csv) ;; *) continue ;; esac
      if ! cmp -s "$f" "docs/availability/$b"; then
        echo "docs/availability/$b differs from what the code produces now (bash scripts/availability_outputs.sh)" >&2
        diff "docs/availability/$b" "$f" | head -10 >&2 || true
        status=1
      fi
    else
      cp "$f" "docs/availability/$b"
    fi
  done
  rm -f "$TMP"/availability_"$name".*
done
[ $MODE = write ] && echo "rewrote docs/availability/availability_{esbc_nav,maast_g24e24,maast_g24e24_fde,maast_g24e24_galtable,maast_g24e24_ed259a,maast_g24e24_adjusted}.*"
exit $status
