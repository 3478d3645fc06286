#!/usr/bin/env bash
# The main job: a real RINEX file (Esbjerg, ESBC, G+E+C) replayed with an
# injected 30 m step on G15 from 01:00:00 GPST, through the firmware running
# under QEMU (mps2-an386, Cortex-M4), printing each epoch's decision and the
# firmware's NMEA (RMC, VTG, GGA, GSA, GSV, GST, GBS, ZDA), then the summary table.
# Installs what it lacks, quietly (scripts/install-deps.sh: the thumbv7em
# target, qemu-system-arm without recommends).
# Extra arguments go to `raim replay` (e.g. --start 00:55:00 --end 01:05:00).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh main
DATA=../shared/data
cargo run -q --release -p raim-tool -- replay \
    --obs "$DATA/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz" \
    --nav "$DATA/ESBC00DNK_R_20201770000_01D_MN.rnx.gz" \
    --ura-m 0.3 --iono-vertical-m 0.5 --noise-m 0.2 \
    --fault step:G15:30@01:00:00 \
    --target qemu --nmea with-text "$@"
