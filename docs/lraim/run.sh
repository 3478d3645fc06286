#!/usr/bin/env bash
# Regenerates every output in docs/lraim/ (issue 7). From the repo root:
#   cargo build --release -p raim-tool && bash docs/lraim/run.sh
# Seeded: the outputs are reproducible bit for bit (Monte Carlo chunks use
# ChaCha8 streams, independent of the thread count).
set -euo pipefail
cd "$(dirname "$0")"
RAIM=${RAIM:-../../target/release/raim}

# Seed 001 Table 1 (BeiDou, 6 satellites, d = 2): exact + 10^6 MC draws.
$RAIM pci --pfa 1e-3 --pd 0.9 --mc 1000000 --seed 1 < beidou_table1.json > beidou_pd0.9_pfa1e-3.txt
$RAIM pci --pfa 1e-3 --pd 0.9 --design fixed-b --mc 1000000 --seed 1 < beidou_table1.json > beidou_fixedb_pd0.9_pfa1e-3.txt
$RAIM pci --pfa 3.3333e-7 --pd 0.999 --mc 1000000 --seed 1 < beidou_table1.json > beidou_pd0.999_pfa3.3e-7.txt
for k in 1 10 100 1000 10000; do
  $RAIM pci --pfa 1e-3 --pd 0.9 --design fixed-b --kappa $k --mc 0 --json < beidou_table1.json > beidou_fixedb_kappa$k.json
done
$RAIM pci --pfa 1e-3 --pd 0.9 --mc 40000 --seed 1 --plot pci_beidou.png < beidou_table1.json > /dev/null

# Seed-like skies: one low satellite alone in a wide azimuth gap.
$RAIM pci --az 10,75,140,200,255,320,110 --el 75,35,28,40,22,45,8 --pfa 1e-3 --pd 0.9 --mc 1000000 --seed 1 > sky7_pd0.9_pfa1e-3.txt
$RAIM pci --az 10,50,95,200,250,300,340,140 --el 75,40,55,35,50,30,45,12 --pfa 1e-3 --pd 0.9 --mc 1000000 --seed 1 > sky8_pd0.9_pfa1e-3.txt
$RAIM pci --az 10,50,80,220,250,300,340,140,270,20 --el 75,40,55,35,50,30,45,8,20,60 --pfa 1e-3 --pd 0.9 --mc 1000000 --seed 1 > sky10_pd0.9_pfa1e-3.txt
$RAIM pci --az 10,50,80,220,250,300,340,140,230,20,275,320 --el 75,40,55,35,50,30,45,8,20,15,65,25 --pfa 1e-3 --pd 0.9 --mc 1000000 --seed 1 > sky12_pd0.9_pfa1e-3.txt
$RAIM pci --az 10,50,80,220,250,300,340,140,230,20,275,320 --el 75,40,55,35,50,30,45,8,20,15,65,25 --pfa 1e-3 --pd 0.9 --mc 40000 --seed 1 --plot pci_sky12.png > /dev/null

# Campaigns (random skies).
$RAIM campaign single-fault --trials 100000 --n-min 6 --n-max 6 --seed 1 > campaign_single_fault_n6.txt
$RAIM campaign single-fault --trials 150 --n-min 7 --n-max 7 --seed 1 > campaign_single_fault_n7.txt
$RAIM campaign false-alarm --epochs 10000000 --pfa 1e-3,1e-5 --seed 1 > campaign_false_alarm.txt
