#!/usr/bin/env bash
# Runs every test of the project on a fresh machine. Installs what it lacks.
set -euo pipefail
cd "$(dirname "$0")/.."

# The thumbv7em target, clippy, rustfmt; QEMU and gpsd for the firmware
# tests (host-tests/tests/qemu_*.rs), quietly and without recommends.
bash scripts/install-deps.sh test

echo "== fmt"
cargo fmt --all -- --check
echo "== requirements traced to tests, both ways (docs/requirements.toml -> docs/TRACE.md)"
python3 scripts/trace.py --check
echo "== clippy (host workspace)"
cargo clippy --workspace --all-targets -- -D warnings
echo "== docs (every rustdoc warning an error; missing_docs is warned in raim-core and raim-proto)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace
echo "== no_std build of the core for Cortex-M4F"
cargo build -p raim-core --target thumbv7em-none-eabihf --release
cargo build -p raim-core --target thumbv7em-none-eabihf --release --features defmt
echo "== firmware (own workspace: QEMU mps2-an386 and STM32F4 builds, clippy, fmt, docs)"
(cd firmware && cargo fmt -- --check && cargo clippy --release -- -D warnings \
    && RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps && cargo build --release \
    && cargo build --release --no-default-features --features board-stm32f4 --target-dir target/stm32f4-hw \
    && cargo build --release --no-default-features --features board-stm32f4,qemu-netduinoplus2 --target-dir target/stm32f4 \
    && cargo clippy --release --no-default-features --features board-qemu --target-dir target/snapshot -- -D warnings \
    && cargo build --release --no-default-features --features board-qemu --target-dir target/snapshot)
# (the last: the QEMU build without araim/pf/multifault, whose flash
# host-tests/tests/qemu_flash.rs bounds to 128 KiB, issue 10)
echo "== static stack bound of every firmware entry within its stack region (call graph of each release ELF; docs/EVIDENCE.md)"
bash scripts/firmware-evidence.sh
echo "== tests (including the firmware under QEMU: host-tests/tests/qemu_*.rs)"
cargo test --workspace --release
# (the host's protocol server runs the device's precision, f32, in every
# build: raim_proto::DevicePrecision; the QEMU tests above compare with it)
echo "== generated doc tables (docs/ESQ.md, docs/MULTIFAULT.md, docs/BUDGET.md) match the code (about 1-2 min)"
bash scripts/doc_tables.sh --check
echo "== docs/PF.md's generated tables reproduce (short mode; the long mode: bash scripts/pf-tables.sh --long)"
bash scripts/pf-tables.sh --check
echo "== the core's own unit tests in the device's precision (their default Stat = f32; ~1 min to build)"
cargo test -p raim-core --release --features test-f32 --lib
echo "== the core's own tests without the optional reconstruction FDE (the 128 KiB flash build's core)"
cargo test -p raim-core --release --no-default-features --lib
