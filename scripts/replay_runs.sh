#!/usr/bin/env bash
# Full replay runs of docs/REPLAY.md: one summary row per scenario (markdown).
# Usage: bash scripts/replay_runs.sh [path/to/raim]   (default: release build)
set -euo pipefail
cd "$(dirname "$0")/.."
R=${1:-target/release/raim}
[ -x "$R" ] || cargo build --release -q -p raim-tool
D=../shared/data
G="--ura-m 0.3 --iono-vertical-m 0.5 --noise-m 0.2"
O="--obs $D/07590920.05o --nav $D/07590920.05n --systems G --mask-deg 15 $G"
E="--obs $D/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz --nav $D/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"
P="--obs $D/GEOP092I.24o.gz --nav $D/CORD00ARG_R_20240920000_01D_MN.rnx.gz"
ROW='import json,sys
s=json.loads(sys.stdin.read().splitlines()[-1])["summary"]
f=lambda v: "-" if v is None else (f"{v:.1f}" if isinstance(v,float) else str(v))
keys=["epochs","solved","ok","excluded","alarms","faulted_epochs","correct_exclusions","wrong_exclusions","missed_detections","false_alarms","false_exclusions","detection_delay_s","bias_at_detection_m","error_h_median_m","error_h_max_m","error_v_max_m","misleading"]
print("|", " | ".join(f(s[k]) for k in keys), "| %.2f |" % s["clean_d2_per_dof_mean"])'
run() { local name="$1"; shift; printf '| %s ' "$name"; "$R" replay "$@" --json --quiet | python3 -c "$ROW"; }
run "0759 clean" $O
run "0759 step 50 m G24" $O --fault step:G24:50@00:20:00
run "0759 ramp 0.1 m/s G24" $O --fault ramp:G24:0.1@00:20:00
run "0759 step 10 m G24" $O --fault step:G24:10@00:20:00
run "0759 step 5 m G24" $O --fault step:G24:5@00:20:00
run "ESBC clean" $E $G
run "ESBC step 20 m G15" $E $G --fault step:G15:20@01:00:00
run "ESBC step 30 m G15" $E $G --fault step:G15:30@01:00:00
run "ESBC step 50 m G15" $E $G --fault step:G15:50@01:00:00
run "ESBC 50 m G15+G28" $E $G --fault step:G15+G28:50@01:00:00
run "ESBC clock jump 300 m" $E $G --fault clock:300@01:00:00
run "ESBC Galileo bias 20 m" $E $G --fault step:E:20@01:00:00
run "ESBC t3 noise 1 m (seed 7)" $E $G --fault noise:all:t3:1.0 --seed 7
run "GEOP G+E clean (default sigma)" $P --systems GE
run "GEOP G+E+C clean (default sigma)" $P --systems GEC
run "ESBC clean, default sigma" $E
run "ESBC 20 m G15, default sigma" $E --fault step:G15:20@01:00:00
