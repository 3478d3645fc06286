#!/usr/bin/env bash
# What the STM32F4 build would need to carry the RTCM 3 stream receiver
# beside ARAIM and the particle filter (issue 34, docs/FLASH.md "STM32F4:
# the stream beside ARAIM and the PF"). Builds the STM32F4 hardware layout
# with the firmware's `rtcm` feature added, first as it is (the linker
# reports by how much SRAM overflows), then once more with the layout's
# SRAM widened to 512 KiB so that it links and each static's size can be
# read (llvm-nm --size-sort) and the server broken down from the DWARF
# (scripts/dwarf_layout.py). memory-stm32f4.x is restored on exit. The
# probe ELF is kept as firmware/target/elf/stm32f4-rtcm-probe; the shared
# target's last build is then the probe's, so rebuild the ELF you test
# afterwards (scripts/test.sh rebuilds every one). Needs llvm-nm,
# llvm-size, llvm-dwarfdump (the `llvm` package).
set -euo pipefail
cd "$(dirname "$0")/.."
FEATURES=board-stm32f4,rtcm
ELF=firmware/target/thumbv7em-none-eabihf/release/raim-firmware
echo "== as laid out (memory-stm32f4.x: 128 KiB SRAM, 64 KiB CCM)"
if out=$(cd firmware && cargo build --release --no-default-features --features "$FEATURES" 2>&1); then
    echo "  links"
else
    echo "$out" | grep -E "will not fit|overflowed" || { echo "$out"; exit 1; }
fi
BACKUP=$(mktemp)
cp memory-stm32f4.x "$BACKUP"
trap 'cp "$BACKUP" memory-stm32f4.x; rm -f "$BACKUP"' EXIT
sed -i 's/RAM    : ORIGIN = 0x20000000, LENGTH = 128K/RAM    : ORIGIN = 0x20000000, LENGTH = 512K/' memory-stm32f4.x
(cd firmware && cargo build --release --no-default-features --features "$FEATURES" 2>&1) | grep -E "^error" && exit 1
mkdir -p firmware/target/elf
cp "$ELF" firmware/target/elf/stm32f4-rtcm-probe
PROBE=firmware/target/elf/stm32f4-rtcm-probe
echo "== with the stream, SRAM widened to link ($PROBE)"
llvm-size -A "$PROBE" | awk '$1 ~ /^\.(text|rodata|data|bss|uninit|ccmram)$/ {printf "  %-8s %8d B\n", $1, $2}'
echo "  largest statics (llvm-nm --size-sort):"
llvm-nm -S --size-sort -C "$PROBE" | awk '$3 ~ /^[dDbB]$/' | tail -4 | while read -r _ size kind name; do
    printf "    %8d B %s %s\n" "$((16#$size))" "$kind" "$name"
done
for s in Server StreamState "StreamReceiver<32, 256>" "EphemerisStore<256, 48>"; do
    python3 scripts/dwarf_layout.py "$PROBE" "$s" 500
done
