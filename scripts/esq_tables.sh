#!/usr/bin/env bash
# The tables of docs/ESQ.md (issue 13, seed 003's own claims), on the shared
# real data. Writes docs/esq/*.txt. About a minute in a release build.
#   bash scripts/esq_tables.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p raim-tool
R=./target/release/raim
OUT=docs/esq
mkdir -p "$OUT"
G="--ura-m 0.3 --iono-vertical-m 0.5 --noise-m 0.2"
O="--obs ../shared/data/07590920.05o --nav ../shared/data/07590920.05n --systems G --mask-deg 15 --esq-pconst 1e-8"
E="--obs ../shared/data/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz --nav ../shared/data/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"

run() { # file, label, args...
  local f=$1 label=$2; shift 2
  { echo "### $label"; echo "\$ raim replay $*"; "$R" replay "$@"; echo; } >>"$f"
}

# 1. ESQ: N*, dT_e, solves saved, and the cost on faults.
f=$OUT/esq_cost.txt; : >"$f"
run "$f" "ESBC clean" $E $G --esq --quiet
run "$f" "ESBC step 10 m G15" $E $G --esq --quiet --fault step:G15:10@01:00:00
run "$f" "ESBC step 5 m G15" $E $G --esq --quiet --fault step:G15:5@01:00:00
run "$f" "ESBC ramp 0.01 m/s G15" $E $G --esq --quiet --fault ramp:G15:0.01@01:00:00
run "$f" "ESBC ramp 0.05 m/s G15" $E $G --esq --quiet --fault ramp:G15:0.05@01:00:00
run "$f" "0759 clean" $O $G --esq --quiet
run "$f" "0759 step 10 m G24" $O $G --esq --quiet --fault step:G24:10@00:20:00
run "$f" "0759 ramp 0.01 m/s G24" $O $G --esq --quiet --fault ramp:G24:0.01@00:20:00
run "$f" "ESBC window T 600 s" $E $G --esq --quiet --esq-window-s 600
run "$f" "ESBC window T 120 s" $E $G --esq --quiet --esq-window-s 120

# 2. MCUSUM on decorrelated samples: the correlation time, then dT_e.
f=$OUT/esq_mcusum.txt; : >"$f"
for spec in "" "--fault step:G15:5@01:00:00" "--fault step:G15:10@01:00:00" "--fault ramp:G15:0.01@01:00:00"; do
  run "$f" "ESBC ${spec:-clean}, tau_c" $E $G --mcusum --esq-mcusum $spec
  run "$f" "ESBC ${spec:-clean}, dT_e (240 s)" $E $G --mcusum --esq-mcusum --esq-decimate-s 240 $spec
done
for spec in "" "--fault step:G24:5@00:20:00" "--fault step:G24:10@00:20:00" "--fault ramp:G24:0.01@00:20:00"; do
  run "$f" "0759 ${spec:-clean}, tau_c" $O $G --mcusum --esq-mcusum $spec
  run "$f" "0759 ${spec:-clean}, dT_e (300 s)" $O $G --mcusum --esq-mcusum --esq-decimate-s 300 $spec
done

# 3. PCA against ARAIM and the snapshot test: constellation-wide faults on ESBC.
f=$OUT/pca_esbc.txt; : >"$f"
run "$f" "ESBC clean" $E $G --pca --quiet
for sys in E C; do
  for b in 5 10 20 50; do run "$f" "ESBC $sys-wide bias $b m" $E $G --pca --quiet --fault step:$sys:$b@01:00:00; done
  for r in 0.01 0.05; do run "$f" "ESBC $sys-wide ramp $r m/s" $E $G --pca --quiet --fault ramp:$sys:$r@01:00:00; done
  for x in 10 50 200; do run "$f" "ESBC $sys ephemeris radial $x m" $E $G --pca --quiet --eph-fault $sys:$x@01:00:00; done
done
run "$f" "ESBC single satellite step 10 m G15 (reference)" $E $G --pca --quiet --fault step:G15:10@01:00:00
run "$f" "0759 clean" $O $G --pca --quiet
echo "wrote $OUT/esq_cost.txt $OUT/esq_mcusum.txt $OUT/pca_esbc.txt"
