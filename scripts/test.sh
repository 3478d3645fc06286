#!/usr/bin/env bash
# Runs every test of the project on a fresh machine. Installs what it lacks.
set -euo pipefail
cd "$(dirname "$0")/.."

# The thumbv7em target, clippy, rustfmt; QEMU and gpsd for the firmware
# tests (host-tests/tests/qemu_*.rs), quietly and without recommends.
bash scripts/install-deps.sh test

# Each step's wall time, printed as a table when the script ends (at the
# end, or at the step that failed): `step NAME` ends the previous step
# and starts the next. Timing only; it changes nothing that runs.
STEP_NAMES=()
STEP_US=()
STEP_NAME=""
STEP_START=0
now_us() { echo "${EPOCHREALTIME/./}"; }
SUITE_START=$(now_us)
step() {
    local now
    now=$(now_us)
    if [ -n "$STEP_NAME" ]; then
        STEP_NAMES+=("$STEP_NAME")
        STEP_US+=("$((now - STEP_START))")
    fi
    STEP_NAME=$1
    STEP_START=$now
    if [ -n "$STEP_NAME" ]; then echo "== $STEP_NAME"; fi
}
seconds() { printf '%6d.%d' "$(($1 / 1000000))" "$(($1 % 1000000 / 100000))"; }
step_times() {
    local rc=$? last=$STEP_NAME i
    step ""
    echo
    if [ "$rc" -ne 0 ]; then
        echo "== wall time per step, s (stopped by a failure in: $last)"
    else
        echo "== wall time per step, s"
    fi
    for i in "${!STEP_NAMES[@]}"; do
        echo "$(seconds "${STEP_US[$i]}")  ${STEP_NAMES[$i]}"
    done
    echo "$(seconds "$(($(now_us) - SUITE_START))")  total (the install step aside)"
}
trap step_times EXIT

step "fmt"
cargo fmt --all -- --check
step "requirements traced to tests, both ways (docs/requirements.toml -> docs/TRACE.md)"
python3 scripts/trace.py --check
step "clippy (host workspace)"
cargo clippy --workspace --all-targets -- -D warnings
step "docs (every rustdoc warning an error; missing_docs is warned in raim-core and raim-proto)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace
step "no_std build of the core for Cortex-M4F"
cargo build -p raim-core --target thumbv7em-none-eabihf --release
cargo build -p raim-core --target thumbv7em-none-eabihf --release --features defmt
# The firmware: its own workspace (QEMU mps2-an386 and STM32F4 builds,
# clippy, fmt, docs), one step per command. Every build shares one target
# directory (firmware/target), so the dependency tree a configuration
# shares with another is built once (the two STM32F4 builds differ only in
# the firmware crate's memory layout). A build's ELF is copied to
# firmware/target/elf/ before the next one overwrites it, and the tests
# take the copies ($RAIM_FIRMWARE_ELF, $RAIM_FIRMWARE_ELF_STM32F4,
# $RAIM_FIRMWARE_ELF_SNAPSHOT, $RAIM_FIRMWARE_ELF_STREAM, crates/raim-qemu). The default build goes
# last, so that firmware/target/thumbv7em-none-eabihf/release/raim-firmware
# is the default firmware afterwards, as before.
FW_ELF=firmware/target/thumbv7em-none-eabihf/release/raim-firmware
keep_elf() { mkdir -p firmware/target/elf && cp "$FW_ELF" "firmware/target/elf/$1"; }
step "firmware: fmt, clippy (default features)"
(cd firmware && cargo fmt -- --check && cargo clippy --release -- -D warnings)
step "firmware: docs"
(cd firmware && RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps)
step "firmware: build, STM32F4 hardware layout"
(cd firmware && cargo build --release --no-default-features --features board-stm32f4)
keep_elf stm32f4-hw
# (with a 30 s pause on the link, RAIM_TEST_LINK_IDLE_S, as the
# mps2-an386 streaming build below: a streaming test must not see a loaded
# host's stall of QEMU as a pause; the 0.25 s pause itself is checked on
# the default mps2-an386 build, docs/EVIDENCE.md)
step "firmware: build, STM32F4 for QEMU netduinoplus2"
(cd firmware && RAIM_TEST_LINK_IDLE_S=30 cargo build --release --no-default-features --features board-stm32f4,qemu-netduinoplus2)
keep_elf stm32f4-netduinoplus2
step "firmware: build, STM32F4 with the stream (hardware layout, and for QEMU netduinoplus2 with the 30 s link pause; docs/FLASH.md \"STM32F4: the stream\")"
(cd firmware && cargo build --release --no-default-features --features board-stm32f4,rtcm)
keep_elf stm32f4-stream-hw
(cd firmware && RAIM_TEST_LINK_IDLE_S=30 cargo build --release --no-default-features --features board-stm32f4,qemu-netduinoplus2,rtcm)
keep_elf stm32f4-stream-netduinoplus2
step "firmware: clippy and build, QEMU snapshot-only"
(cd firmware && cargo clippy --release --no-default-features --features board-qemu -- -D warnings \
    && cargo build --release --no-default-features --features board-qemu)
keep_elf snapshot
# (the QEMU build without araim/pf/multifault, whose flash
# host-tests/tests/qemu_flash.rs bounds to 128 KiB, issue 10)
step "firmware: build, QEMU mps2-an386 with a 1 s time-to-alert (the hung-loop alarm test)"
(cd firmware && RAIM_TIME_TO_ALERT_S=1 cargo build --release --features tta-record)
keep_elf qemu-tta1
step "firmware: build, QEMU mps2-an386 with a 30 s link pause (the streaming tests; docs/EVIDENCE.md)"
(cd firmware && RAIM_TEST_LINK_IDLE_S=30 cargo build --release)
keep_elf qemu-stream
step "firmware: build, QEMU mps2-an386 (default features)"
(cd firmware && cargo build --release)
keep_elf qemu
export RAIM_FIRMWARE_ELF_TTA1="$PWD/firmware/target/elf/qemu-tta1"
export RAIM_FIRMWARE_ELF_STREAM="$PWD/firmware/target/elf/qemu-stream"
export RAIM_FIRMWARE_ELF="$PWD/firmware/target/elf/qemu"
export RAIM_FIRMWARE_ELF_STM32F4="$PWD/firmware/target/elf/stm32f4-netduinoplus2"
export RAIM_FIRMWARE_ELF_STM32F4_STREAM="$PWD/firmware/target/elf/stm32f4-stream-netduinoplus2"
export RAIM_FIRMWARE_ELF_SNAPSHOT="$PWD/firmware/target/elf/snapshot"
step "static stack bound of every firmware entry within its stack region (call graph of each release ELF; docs/EVIDENCE.md)"
bash scripts/firmware-evidence.sh
step "tests (including the firmware under QEMU: host-tests/tests/qemu_*.rs)"
cargo test --workspace --release
# (the host's protocol server runs the device's precision, f32, in every
# build: raim_proto::DevicePrecision; the QEMU tests above compare with it)
step "generated doc tables (docs/ESQ.md, docs/MULTIFAULT.md, docs/BUDGET.md) match the code (about 1-2 min)"
bash scripts/doc_tables.sh --check
step "docs/PF.md's generated tables reproduce (short mode; the long mode: bash scripts/pf-tables.sh --long)"
bash scripts/pf-tables.sh --check
step "the core's own unit tests in the device's precision (their default Stat = f32; ~1 min to build)"
cargo test -p raim-core --release --features test-f32 --lib
step "the core's own tests without the optional reconstruction FDE (the 128 KiB flash build's core)"
cargo test -p raim-core --release --no-default-features --lib
step "the STM32F4 stream build's capacities (raim-server ram-192k + rtcm: 24 satellites, the 25th typed; raim-nav's stream tests with its ram-192k holding areas)"
cargo test -p raim-server --release --features ram-192k,rtcm the_stm32f4_stream_build
cargo test -p raim-server --release --features ram-192k,rtcm araim::
cargo test -p raim-nav --release --features rtcm,ram-192k --lib
step "qemu_stm32f4 on the STM32F4 stream build (8 KiB of stack over each session's high water; the 32-satellite epoch refused typed at 24; docs/FLASH.md)"
RAIM_FIRMWARE_ELF_STM32F4="$RAIM_FIRMWARE_ELF_STM32F4_STREAM" cargo test --release -p host-tests --test qemu_stm32f4
step "structural coverage of raim-core, raim-nav, raim-proto, raim-server not under docs/coverage_floor.txt (their own unit tests, instrumented on the pinned nightly; docs/EVIDENCE.md)"
bash scripts/coverage.sh --check
