#!/usr/bin/env bash
# The main job: the example epochs (docs/FORMATS.md) through the core on the
# host, printing one decision per epoch. Installs what it lacks.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo run -q --release -p raim-tool -- snapshot --input host-tests/vectors/snapshot_example.jsonl "$@"
