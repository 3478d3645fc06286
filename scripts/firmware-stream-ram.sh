#!/usr/bin/env bash
# What the STM32F4 build needs to carry the RTCM 3 stream receiver beside
# ARAIM and the particle filter (issue 34, docs/FLASH.md "STM32F4: the
# stream beside ARAIM and the PF"). Builds the STM32F4 hardware layout
# with the firmware's `rtcm` feature added:
# 1. as laid out (memory-stm32f4.x: 128 KiB SRAM, 64 KiB CCM). When it
#    links, the ELF is kept as firmware/target/elf/stm32f4-rtcm and the
#    margins are reported: SRAM and CCM left, the stack region (guard to
#    the top of SRAM, as scripts/firmware-memory.sh reads it) against the
#    static stack bound (scripts/firmware_callgraph.py: main plus the
#    deepest exception handler and its frame, the bound
#    scripts/firmware-evidence.sh checks). When it does not link, the
#    linker's overflow.
# 2. once more with the layout's SRAM widened to 512 KiB, so that it always
#    links and each static's size can be read (llvm-nm --size-sort) and the
#    server broken down from the DWARF (scripts/dwarf_layout.py).
# memory-stm32f4.x is restored on exit. The probe ELF is kept as
# firmware/target/elf/stm32f4-rtcm-probe; the shared target's last build
# is then the probe's, so rebuild the ELF you test afterwards
# (scripts/test.sh rebuilds every one). Needs llvm-nm, llvm-size,
# llvm-objdump, llvm-dwarfdump (the `llvm` package).
set -euo pipefail
cd "$(dirname "$0")/.."
FEATURES=board-stm32f4,rtcm
ELF=firmware/target/thumbv7em-none-eabihf/release/raim-firmware
mkdir -p firmware/target/elf
echo "== as laid out (memory-stm32f4.x: 128 KiB SRAM, 64 KiB CCM)"
if out=$(cd firmware && cargo build --release --no-default-features --features "$FEATURES" 2>&1); then
    cp "$ELF" firmware/target/elf/stm32f4-rtcm
    LAID=firmware/target/elf/stm32f4-rtcm
    echo "  links ($LAID)"
    llvm-size -A "$LAID" | awk '
        $1 ~ /^\.(data|bss|uninit)$/ {ram += $2}
        $1 == ".ccmram" {ccm += $2}
        END {printf "  static SRAM %d B of 131072 (%d B left for the MPU guard and the stack); CCM %d B of 65536 (%d B left)\n", ram, 131072 - ram, ccm, 65536 - ccm}'
    json=$(mktemp)
    python3 scripts/firmware_callgraph.py "$LAID" --json "$json" >/dev/null
    python3 - "$json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
main = r["entries"]["main"]["stack_bytes"]
bound = r["bound_bytes"]
region = r["stack_region_bytes"]
print(f"  stack region {region} B (guard to the top of SRAM); static bound {bound} B"
      f" (main {main} B + the deepest exception handler and its frame)")
margin = region - bound
verdict = "fits" if margin >= 0 else "DOES NOT FIT"
print(f"  stack margin {margin} B ({100.0 * margin / bound:.0f} % of the bound): {verdict}")
PY
    rm -f "$json"
else
    echo "$out" | grep -E "will not fit|overflowed" || { echo "$out"; exit 1; }
fi
BACKUP=$(mktemp)
cp memory-stm32f4.x "$BACKUP"
trap 'cp "$BACKUP" memory-stm32f4.x; rm -f "$BACKUP"' EXIT
sed -i 's/RAM    : ORIGIN = 0x20000000, LENGTH = 128K/RAM    : ORIGIN = 0x20000000, LENGTH = 512K/' memory-stm32f4.x
(cd firmware && cargo build --release --no-default-features --features "$FEATURES" 2>&1) | grep -E "^error" && exit 1
cp "$ELF" firmware/target/elf/stm32f4-rtcm-probe
PROBE=firmware/target/elf/stm32f4-rtcm-probe
echo "== with the stream, SRAM widened to link ($PROBE)"
llvm-size -A "$PROBE" | awk '$1 ~ /^\.(text|rodata|data|bss|uninit|ccmram)$/ {printf "  %-8s %8d B\n", $1, $2}'
echo "  largest statics (llvm-nm --size-sort):"
llvm-nm -S --size-sort -C "$PROBE" | awk '$3 ~ /^[dDbB]$/' | tail -4 | while read -r _ size kind name; do
    printf "    %8d B %s %s\n" "$((16#$size))" "$kind" "$name"
done
# The types' names carry their capacities: read them from the DWARF.
types=$(llvm-dwarfdump --debug-info "$PROBE" | grep -oE 'DW_AT_name\s+\("(StreamReceiver|EphemerisStore)<[0-9, ]+>"\)' \
    | sed -E 's/.*\("(.*)"\)/\1/' | sort -u)
python3 scripts/dwarf_layout.py "$PROBE" Server 500
python3 scripts/dwarf_layout.py "$PROBE" StreamState 500
while IFS= read -r t; do
    [ -n "$t" ] && python3 scripts/dwarf_layout.py "$PROBE" "$t" 500
done <<< "$types"
