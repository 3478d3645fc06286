#!/usr/bin/env bash
# ARAIM availability (issue 36): speed and memory of `raim availability`
# on the MAAST G24+E24 scenario (docs/runs/availability_maast_g24e24.toml),
# detection only, at world grids of 10, 5 and 2.5 degrees, on 1 and 2
# threads; then with exclusion counted by continuity (docs/runs/availability_maast_g24e24_fde.toml)
# at 10 degrees. `--fde-only` runs the last part alone. Prints per run: users x epochs, wall time, CPU time (user+sys),
# user-epochs per wall second and per CPU second, maximum resident memory.
# Numbers in BENCHMARKS.md "ARAIM availability" and docs/AVAILABILITY.md.
# Usage: bash scripts/availability_bench.sh   (from the repository root)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p raim-tool
RAIM=target/release/raim
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
DATA=$(cd ../shared/data && pwd)
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%-6s %-7s %-9s %8s %8s %14s %14s %10s %9s\n' grid threads users*ep wall_s cpu_s "ue/s(wall)" "ue/s(cpu)" maxrss_MB coverage
bench() { # run-file grid-step threads label
  sed -e "s|step_deg = 10.0|step_deg = $2|" \
      -e "s|\.\./\.\./\.\./shared/data|$DATA|" \
      "$1" > "$TMP/run.toml"
  /usr/bin/time -f "%e %U %S %M" -o "$TMP/time" \
    "$RAIM" availability --run "$TMP/run.toml" --out "$TMP" --threads "$3" 2> "$TMP/err"
  read -r wall user sys rss < "$TMP/time"
  ue=$(grep -o '^[0-9]* user-epochs' "$TMP/err" | cut -d' ' -f1)
  cov=$(grep -o 'coverage at 0.995: [0-9.]*' "$TMP/err" | cut -d' ' -f4)
  awk -v s="$2$4" -v t="$3" -v ue="$ue" -v w="$wall" -v u="$user" -v y="$sys" -v r="$rss" -v c="$cov" \
    'BEGIN { printf "%-6s %-7s %-9s %8.2f %8.2f %14.0f %14.0f %10.1f %9s\n", s, t, ue, w, u + y, ue / w, ue / (u + y), r / 1024, c }'
}
if [ "${1:-}" != "--fde-only" ]; then
  for step in 10 5 2.5; do
    for threads in 1 2; do
      bench docs/runs/availability_maast_g24e24.toml "$step" "$threads" ""
    done
  done
fi
for threads in 1 2; do
  bench docs/runs/availability_maast_g24e24_fde.toml 10 "$threads" "+FDE"
done
