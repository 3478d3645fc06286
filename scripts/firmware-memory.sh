#!/usr/bin/env bash
# Flash, static RAM per section and region, and the biggest items of each
# firmware build (docs/FLASH.md). Run from the repository root after the
# builds of scripts/test.sh:
#   (cd firmware && cargo build --release \
#     && cargo build --release --no-default-features --features board-qemu --target-dir target/snapshot \
#     && cargo build --release --no-default-features --features board-stm32f4 --target-dir target/stm32f4-hw \
#     && cargo build --release --no-default-features --features board-stm32f4,qemu-netduinoplus2 --target-dir target/stm32f4)
#   bash scripts/firmware-memory.sh
# Needs llvm-size and llvm-nm (the `llvm` package).
set -euo pipefail
ELF=thumbv7em-none-eabihf/release/raim-firmware
for build in "QEMU mps2-an386, default:firmware/target/$ELF" \
             "QEMU mps2-an386, snapshot:firmware/target/snapshot/$ELF" \
             "STM32F4 (hardware layout):firmware/target/stm32f4-hw/$ELF" \
             "STM32F4 (netduinoplus2 layout):firmware/target/stm32f4/$ELF"; do
    name=${build%%:*}
    elf=${build#*:}
    [ -f "$elf" ] || { echo "== $name: no $elf"; continue; }
    echo "== $name ($elf)"
    llvm-size -A "$elf" | awk '$1 ~ /^\.(vector_table|text|rodata|raim_key|raim_config|data|bss|uninit|ccmram)$/ {printf "  %-14s %8d B at 0x%08x\n", $1, $2, $3}'
    llvm-size -A "$elf" | awk '
        $1 ~ /^\.(vector_table|text|rodata|raim_key|raim_config|data)$/ {flash += $2}
        $1 ~ /^\.(data|bss|uninit)$/ {ram += $2}
        $1 == ".ccmram" {ccm += $2}
        END {printf "  flash %d B; static RAM %d B (SRAM), %d B (CCM)\n", flash, ram, ccm}'
    sheap=$(llvm-nm "$elf" | awk '$3 == "__sheap" {print $1}')
    top=$(llvm-nm "$elf" | awk '$3 == "_stack_start" {print $1}')
    # The stack: from the top of SRAM down to the 1 KiB MPU guard above
    # the statics (firmware/src/guard.rs).
    python3 -c "s=int('$sheap',16); t=int('$top',16); g=(s+1023)//1024*1024; print(f'  stack {t-g-1024} B (statics end 0x{s:08x}, guard 0x{g:08x}-0x{g+1024:08x}, top 0x{t:08x})')"
    echo "  biggest items:"
    llvm-nm -S --size-sort -C "$elf" | tail -8 | while read -r _ size kind name; do
        printf "    %8d B %s %s\n" "$((16#$size))" "$kind" "$name"
    done
done
