#!/usr/bin/env bash
# docs/AVAILABILITY.md "The Galileo airborne curve" (issue 36): two generated
# tables, between the markers <!-- BEGIN generated: NAME --> and
# <!-- END generated: NAME -->:
#   availability-airborne-curves    the airborne curves side by side
#                                   (cargo run --release -p raim-availability --example airborne_curves)
#   availability-airborne-coverage  the MAAST scenario under each curve, from the
#                                   committed summaries and per-user CSVs of
#                                   docs/availability/availability_maast_g24e24{,_galtable,_ed259a}.*
#                                   (written by scripts/availability_outputs.sh, which checks them)
#   bash scripts/availability_airborne.sh           # rewrite the two tables
#   bash scripts/availability_airborne.sh --check   # compare; exit 1 on a difference
# scripts/doc_tables.sh calls it (in its --check mode with --check), after
# scripts/availability_outputs.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=write
case ${1:-} in
  --check) MODE=check ;;
  "") ;;
  *) echo "usage: $0 [--check]" >&2; exit 2 ;;
esac
cargo build --release -q -p raim-availability --example airborne_curves
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
./target/release/examples/airborne_curves > "$TMP/availability-airborne-curves"
python3 - docs/availability "$TMP/availability-airborne-coverage" <<'EOF'
import csv, json, sys
d, out = sys.argv[1], sys.argv[2]
runs = [
    ("maast_g24e24", "GPS L1/L5 curves for both (the ADD's; the default)"),
    ("maast_g24e24_galtable", "Galileo: E1/E5a table (MAAST v1.4a); GPS: L1/L5 curves"),
    ("maast_g24e24_ed259a", "both: ED-259A as MAAST for ARAIM 2, with its iono residual"),
]
def users(name):
    with open(f"{d}/availability_{name}.users.csv") as f:
        return [(float(r["availability"]), float(r["vpl_p995_m"])) for r in csv.DictReader(f)]
base = users(runs[0][0])
rows = [
    "| airborne model | run file | coverage at 99.5 % | at 99 % | mean availability | worst user VPL (99.5th pct) | users less / more available than the default | users with a lower / higher VPL (99.5th pct) | per-user VPL (99.5th pct) against the default: mean, range |",
    "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
]
for name, label in runs:
    s = json.load(open(f"{d}/availability_{name}.summary.json"))
    cov = {c["level"]: c["coverage"] for c in s["coverage"]}
    u = users(name)
    assert len(u) == len(base)
    less = sum(a < b[0] for (a, _), b in zip(u, base))
    more = sum(a > b[0] for (a, _), b in zip(u, base))
    rel = [(v - b[1]) / b[1] * 100 for (_, v), b in zip(u, base)]
    ch = "-" if name == runs[0][0] else f"{sum(rel) / len(rel):+.2f} %, {min(rel):+.2f} .. {max(rel):+.2f} %"
    lm = "-" if name == runs[0][0] else f"{less} / {more}"
    lower = sum(v < b[1] for (_, v), b in zip(u, base))
    higher = sum(v > b[1] for (_, v), b in zip(u, base))
    lh = "-" if name == runs[0][0] else f"{lower} / {higher}"
    rows.append(
        f"| {label} | docs/runs/availability_{name}.toml | {cov[0.995] * 100:.2f} % | {cov[0.99] * 100:.2f} % "
        f"| {s['mean_availability_area_weighted'] * 100:.3f} % | {s['worst_user_vpl_percentile_m']:.2f} m | {lm} | {lh} | {ch} |"
    )
open(out, "w").write("\n".join(rows) + "\n")
EOF
cp docs/AVAILABILITY.md "$TMP/AVAILABILITY.md"
for name in availability-airborne-curves availability-airborne-coverage; do
  grep -q "<!-- BEGIN generated: $name -->" "$TMP/AVAILABILITY.md" || { echo "docs/AVAILABILITY.md: no marker $name" >&2; exit 1; }
  awk -v b="<!-- BEGIN generated: $name -->" -v e="<!-- END generated: $name -->" -v f="$TMP/$name" '
    index($0, b) == 1 { print; while ((getline l < f) > 0) print l; skip = 1; next }
    index($0, e) == 1 { skip = 0 }
    !skip { print }' "$TMP/AVAILABILITY.md" > "$TMP/next.md"
  mv "$TMP/next.md" "$TMP/AVAILABILITY.md"
done
if [ $MODE = check ]; then
  if ! diff -u docs/AVAILABILITY.md "$TMP/AVAILABILITY.md"; then
    echo "docs/AVAILABILITY.md: the airborne tables differ from what the code produces now (bash scripts/availability_airborne.sh)" >&2
    exit 1
  fi
  exit 0
fi
cp "$TMP/AVAILABILITY.md" docs/AVAILABILITY.md
echo "rewrote the availability-airborne-curves and availability-airborne-coverage tables of docs/AVAILABILITY.md"
