#!/bin/bash
# Compares two `raim` builds on the ARAIM replay's CI window (ESBC
# 00:30-01:30; docs/ARAIM.md "Replay on real data") and on `raim araim`
# with the App. D vector: per run, the epochs whose decision, FDE,
# exclusions, availability, detection or error differ, and the largest
# change of the VPL in force and of the position error.
# usage: scripts/araim_replay_compare.sh RAIM_BEFORE RAIM_AFTER
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
D="$root/../shared/data"
out=$(mktemp -d)
P=(replay --obs "$D/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz" --nav "$D/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"
   --reference header --start 00:30:00 --end 01:30:00 --araim --json)
declare -A runs=(
  [ge_g15]="--systems GE --fault step:G15:30@01:00:00"
  [gec]="--systems GEC"
  [ge_const]="--systems GE --araim-const-fault E:0:0,20,-20@01:00:00"
  [gec_const]="--systems GEC --araim-const-fault E:0:0,20,-20@01:00:00"
  [ge_if]="--systems GE --code G=C1W+C2W --code E=C1C+C5Q"
  [gec_iono]="--systems GEC --araim-iono-m 0.5"
)
for side in before after; do
  bin=$1; [ "$side" = after ] && bin=$2
  mkdir -p "$out/$side"
  "$bin" araim --json --modes --input "$root/host-tests/vectors/add_v3_appendix_d.json" > "$out/$side/araim_cmd.txt"
  for n in "${!runs[@]}"; do
    # shellcheck disable=SC2086
    "$bin" "${P[@]}" ${runs[$n]} > "$out/$side/$n.txt"
  done
done
cmp -s "$out/before/araim_cmd.txt" "$out/after/araim_cmd.txt" && echo "raim araim: identical" || echo "raim araim: DIFFERS"
python3 - "$out" "${!runs[@]}" <<'PY'
import json, sys
out, names = sys.argv[1], sys.argv[2:]
for n in sorted(names):
    a = [json.loads(l) for l in open(f"{out}/before/{n}.txt")][:-1]
    b = [json.loads(l) for l in open(f"{out}/after/{n}.txt")][:-1]
    key = lambda r: (r["fde"], r["excluded"], r["available"], r["detection_passed"], r.get("error"))
    dec = sum(key(x) != key(y) for x, y in zip(a, b))
    dvpl = max(abs((x["vpl_m"] or 0) - (y["vpl_m"] or 0)) for x, y in zip(a, b))
    dpos = max((max(abs(p - q) for p, q in zip(x["error_enu_m"], y["error_enu_m"]))
                for x, y in zip(a, b) if x["error_enu_m"] and y["error_enu_m"]), default=0.0)
    print(f"{n}: {len(a)} epochs, {dec} differ in decision; max |dVPL| {dvpl:.1e} m, max |dpos| {dpos:.1e} m")
PY
rm -rf "$out"
