#!/usr/bin/env bash
# A 50 m step from 60 s after the start on each GPS (and, on GMSD7 with
# --systems GR, GLONASS) satellite of the two receiver logs (docs/RECEIVERS.md, "Results"): faulted epochs, correct
# exclusions, wrong exclusions, missed detections, alarms, false alarms.
# Usage: bash scripts/receiver_steps.sh   (after cargo build --release -p raim-tool)
set -euo pipefail
cd "$(dirname "$0")/.."
R=target/release/raim
D=../shared/data
row() {
  python3 -c "import json,sys; s=json.loads(sys.stdin.read().splitlines()[-1])['summary']; print(s['faulted_epochs'], s['correct_exclusions'], s['wrong_exclusions'], s['missed_detections'], s['alarms'], s['false_alarms'])"
}
echo "GMSD7 (--rtcm3, --systems G --mask-deg 0, iono-free L1/L2)"
for s in G01 G03 G06 G07 G30 G31; do
  echo "$s $($R replay --rtcm3 $D/GMSD7_20121014.rtcm3 --systems G --mask-deg 0 --fault step:$s:50@+60 --json --keep-going 2>/dev/null | row)"
done
echo "GMSD7 (--rtcm3, --systems GR --mask-deg 0, GPS and GLONASS iono-free L1/L2)"
echo "clean $($R replay --rtcm3 $D/GMSD7_20121014.rtcm3 --systems GR --mask-deg 0 --json --keep-going 2>/dev/null | row)"
for s in G01 G03 G06 G07 G30 G31 R13 R14 R15; do
  echo "$s $($R replay --rtcm3 $D/GMSD7_20121014.rtcm3 --systems GR --mask-deg 0 --fault step:$s:50@+60 --json --keep-going 2>/dev/null | row)"
done
echo "LEA-4T (--ubx, L1 C/A, no Klobuchar in the log)"
for s in G05 G09 G12 G14 G15 G18 G22 G30; do
  echo "$s $($R replay --ubx $D/ubx_20080526.ubx --fault step:$s:50@+60 --json --keep-going 2>/dev/null | row)"
done
echo "LEA-4T with the RINEX default residual-iono sigma (--iono-vertical-m 2.5), for comparison"
for s in G05 G09 G12 G14 G15 G18 G22 G30; do
  echo "$s $($R replay --ubx $D/ubx_20080526.ubx --iono-vertical-m 2.5 --fault step:$s:50@+60 --json --keep-going 2>/dev/null | row)"
done
