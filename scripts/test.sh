#!/usr/bin/env bash
# Runs every test of the project on a fresh machine. Installs what it lacks.
set -euo pipefail
cd "$(dirname "$0")/.."

rustup target add thumbv7em-none-eabihf >/dev/null
rustup component add clippy rustfmt >/dev/null 2>&1 || true

echo "== fmt"
cargo fmt --all -- --check
echo "== clippy (host workspace)"
cargo clippy --workspace --all-targets -- -D warnings
echo "== no_std build of the core for Cortex-M4F"
cargo build -p raim-core --target thumbv7em-none-eabihf --release
cargo build -p raim-core --target thumbv7em-none-eabihf --release --features defmt
echo "== tests"
cargo test --workspace --release
