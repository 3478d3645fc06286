#!/usr/bin/env bash
# ARAIM availability (issue 36): every single-satellite GPS outage of the
# MAAST G24+E24 scenario (docs/runs/availability_maast_g24e24.toml, the
# run file with `remove = [p]` added to its GPS constellation). Per outage:
# the coverage at 99.5 %, and against the full constellation the users
# whose availability fell and rose, with the largest rise (MHSS allows a
# rise: removing a satellite removes its fault mode). docs/AVAILABILITY.md
# "Outages". Usage: bash scripts/availability_outages.sh [PRN...]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p raim-tool
RAIM=target/release/raim
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
DATA=$(cd ../shared/data && pwd)
base() { sed -e "s|\.\./\.\./\.\./shared/data|$DATA|" docs/runs/availability_maast_g24e24.toml; }
base > "$TMP/base.toml"
"$RAIM" availability --run "$TMP/base.toml" --out "$TMP/base" 2> /dev/null
prns=("$@")
[ ${#prns[@]} -eq 0 ] && prns=($(seq 1 24))
printf '%-6s %10s %6s %6s %22s\n' outage coverage fell rose "largest rise (user)"
for p in "${prns[@]}"; do
  base | sed "0,/week_rollovers = 0/s//week_rollovers = 0\nremove = [$p]/" > "$TMP/run.toml"
  "$RAIM" availability --run "$TMP/run.toml" --out "$TMP/out" 2> "$TMP/err"
  cov=$(grep -o 'coverage at 0.995: [0-9.]*' "$TMP/err" | cut -d' ' -f4)
  paste -d, "$TMP/base/availability_maast_g24e24.users.csv" "$TMP/out/availability_maast_g24e24.users.csv" |
    awk -F, -v p="$p" -v c="$cov" 'NR > 1 {
        d = $19 - $7
        if (d < 0) fell++
        if (d > 0) { rose++; if (d > best) { best = d; at = $2 "," $3 " " $7 "->" $19 } }
      }
      END { printf "G%02d    %10s %6d %6d %22s\n", p, c, fell, rose, (rose ? sprintf("+%.4f (%s)", best, at) : "-") }'
done
