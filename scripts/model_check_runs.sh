#!/usr/bin/env bash
# The model check (docs/MODEL_CHECK.md) on the real files: prints the
# markdown tables of docs/MODEL_CHECK.md. Run from the repository root:
#   bash scripts/model_check_runs.sh [path/to/raim]
# Each row is one `raim replay ... --model-check --json` run; the command
# of every row is printed under the tables.
set -euo pipefail
RAIM=${1:-target/release/raim}
[ -x "$RAIM" ] || cargo build -q --release -p raim-tool
D=../shared/data
[ -d "$D" ] || D=/work/shared/data
G="--ura-m 0.3 --iono-vertical-m 0.5 --noise-m 0.2"   # the fitted sigma of docs/REPLAY.md
O="--obs $D/07590920.05o --nav $D/07590920.05n --systems G --mask-deg 15 $G"
E="--obs $D/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz --nav $D/ESBC00DNK_R_20201770000_01D_MN.rnx.gz $G"
P="--obs $D/GEOP092I.24o.gz --nav $D/CORD00ARG_R_20240920000_01D_MN.rnx.gz --systems GE"
R="--rtcm3 $D/GMSD7_20121014.rtcm3 --systems G --mask-deg 0"
U="--ubx $D/ubx_20080526.ubx"
FLOORS="--araim-ura-m 0.3 --araim-ure-m 0.2"             # the ISM at its floors (issue 35)
NOISE="--fault noise:all:t1000:1.0 --seed 35"           # 1 m noise (Student-t, 1000 dof)
G0759="--araim --araim-p-const G=1e-8"                  # GPS only: docs/ARAIM.md
# Spacings: the default (1800 s), and each file's own measured correlation
# time (docs/ESQ.md, mcusum-rho, 1/e, mean removed): 0759 510 s, ESBC
# 1530 s, GEOP and GMSD7 1 s, LEA-4T 23 s.
runs=(
  "clean|0759|snapshot, fitted sigma|$O"
  "clean|0759|snapshot, fitted sigma|$O --model-check-spacing-s 510"
  "clean|ESBC|snapshot, fitted sigma|$E"
  "clean|ESBC|snapshot, fitted sigma|$E --model-check-spacing-s 1530"
  "clean|GEOP|snapshot, default sigma|$P"
  "clean|GEOP|snapshot, default sigma|$P --model-check-spacing-s 1"
  "clean|GMSD7|snapshot, default sigma|$R --model-check-spacing-s 1"
  "clean|LEA-4T|snapshot, default sigma|$U --model-check-spacing-s 23"
  "clean|0759 G|ARAIM, ISM 0.75/0.5|$O $G0759"
  "clean|0759 G|ARAIM, ISM 0.75/0.5|$O $G0759 --model-check-spacing-s 510"
  "clean|ESBC GE|ARAIM, ISM 0.75/0.5|$E --systems GE --araim"
  "clean|ESBC GE|ARAIM, ISM 0.75/0.5|$E --systems GE --araim --model-check-spacing-s 1530"
  "clean|ESBC GEC|ARAIM, ISM 0.75/0.5|$E --araim"
  "clean|ESBC GEC|ARAIM, ISM 0.75/0.5|$E --araim --model-check-spacing-s 1530"
  "clean|GEOP GE|ARAIM, ISM 0.75/0.5, iono 2.5 m|$P --araim --araim-iono-m 2.5"
  "clean|GEOP GE|ARAIM, ISM 0.75/0.5, iono 2.5 m|$P --araim --araim-iono-m 2.5 --model-check-spacing-s 1"
  "model wrong|GEOP GE|ARAIM, ISM 0.75/0.5, no iono term|$P --araim --model-check-spacing-s 1"
  "model wrong|ESBC GE|ARAIM, ISM floors 0.3/0.2|$E --systems GE --araim $FLOORS"
  "model wrong|ESBC GE|ARAIM, ISM floors 0.3/0.2|$E --systems GE --araim $FLOORS --model-check-spacing-s 1530"
  "red team|ESBC GE|ARAIM, ISM floors 0.3/0.2, +1 m noise|$E --systems GE --araim $FLOORS $NOISE"
  "red team|ESBC GE|ARAIM, ISM floors 0.3/0.2, +1 m noise|$E --systems GE --araim $FLOORS $NOISE --model-check-spacing-s 1530"
  "red team|ESBC GEC|ARAIM, ISM floors 0.3/0.2, +1 m noise|$E --araim $FLOORS $NOISE"
  "red team|ESBC GEC|ARAIM, ISM floors 0.3/0.2, +1 m noise|$E --araim $FLOORS $NOISE --model-check-spacing-s 1530"
  "red team|0759 G|ARAIM, ISM floors 0.3/0.2, +1 m noise|$O $G0759 $FLOORS $NOISE"
  "red team|0759 G|ARAIM, ISM floors 0.3/0.2, +1 m noise|$O $G0759 $FLOORS $NOISE --model-check-spacing-s 510"
  "red team|ESBC|snapshot, fitted sigma, +1 m noise|$E $NOISE"
  "red team|ESBC|snapshot, fitted sigma, +1 m noise|$E $NOISE --model-check-spacing-s 1530"
  "red team|0759|snapshot, fitted sigma, +1 m noise|$O $NOISE"
  "red team|0759|snapshot, fitted sigma, +1 m noise|$O $NOISE --model-check-spacing-s 510"
)
echo "| case | file | monitor and model | spacing / window | hours | answered (alarms) | evaluations | rejections | 99 % bound (clean) | smallest p | first declaration (samples after onset) | mean q/dof |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
cmds=()
for r in "${runs[@]}"; do
  IFS='|' read -r kind file model args <<<"$r"
  # shellcheck disable=SC2086
  json=$("$RAIM" replay $args --model-check --json 2>/dev/null)
  KIND="$kind" FILE="$file" MODEL="$model" python3 -c '
import json, os, sys
r = json.loads(sys.stdin.read())["model_check"]
first = "none"
if r["first_rejection_gps_s"] is not None:
    t = r["first_rejection_gps_s"] % 86400
    first = "%02d:%02d:%02d" % (t // 3600, t % 3600 // 60, t % 60)
    if r["samples_to_declaration"] is not None:
        first += " (%d)" % r["samples_to_declaration"]
print("| %s | %s | %s | %g s / %d | %.2f | %d (%d) | %d | %d | %d | %.1e | %s | %.3f |" % (
    os.environ["KIND"], os.environ["FILE"], os.environ["MODEL"], r["spacing_s"], r["window"],
    r["hours"], r["offered"], r["alarms"], r["evaluations"], r["rejections"], r["allowed_99"],
    r["min_p_value"], first, r["mean_q_per_dof"]))
' <<<"$json"
  cmds+=("raim replay ${args//$D/\$D} --model-check")
done
echo
echo "Allocation in every row: P_h = 1e-6 per hour; p per evaluation = P_h / (floor(3600 / spacing) + 1)."
echo
echo "Commands (D=$D; the script adds --json):"
echo '```'
for c in "${cmds[@]}"; do echo "$c"; done
echo '```'
