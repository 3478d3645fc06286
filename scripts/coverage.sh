#!/usr/bin/env bash
# Structural coverage (lines and branches) of the on-device crates by their
# own tests (issue 37; docs/EVIDENCE.md "Structural coverage"):
# raim-core, raim-nav, raim-proto and raim-server, in the features the
# firmware builds (rtcm, pf, araim, multifault).
#
#   bash scripts/coverage.sh           # prints the report; writes target/coverage/summary.txt
#   bash scripts/coverage.sh --check   # also fails if a figure falls below docs/coverage_floor.txt
#
# Figures: llvm-cov's report (lines, branches, regions: the source files
# whole, their in-file test modules included), then the product code alone
# (product_lines, product_branches) and with the justified exceptions of
# docs/coverage_exceptions.txt (justified_lines, justified_branches), by
# scripts/coverage_product.py.
#
# The product builds on stable; only this script uses the pinned nightly
# below, for `-Z coverage-options=branch`, with its own llvm-tools
# (`rustup component add llvm-tools --toolchain $NIGHTLY`, done here).
# The instrumented build has its own target directory.
set -euo pipefail
cd "$(dirname "$0")/.."
NIGHTLY="${RAIM_COVERAGE_TOOLCHAIN:-nightly-2026-05-19}"
if ! rustup run "$NIGHTLY" rustc --version >/dev/null 2>&1; then
    # The machine's nightly, if it is the pinned one under another name.
    if rustup run nightly rustc --version 2>/dev/null | grep -q "2026-05-19"; then
        NIGHTLY=nightly
    else
        rustup toolchain install "$NIGHTLY" --profile minimal >/dev/null 2>&1
    fi
fi
rustup component add llvm-tools --toolchain "$NIGHTLY" >/dev/null 2>&1 || true
sysroot="$(rustup run "$NIGHTLY" rustc --print sysroot)"
bin="$(ls -d "$sysroot"/lib/rustlib/*/bin | head -1)"
PROFDATA="$bin/llvm-profdata"
COV="$bin/llvm-cov"
[ -x "$PROFDATA" ] && [ -x "$COV" ] || { echo "coverage: llvm-tools missing for $NIGHTLY" >&2; exit 1; }

out="$PWD/target/coverage"
rm -rf "$out/profraw"
mkdir -p "$out/profraw"
export CARGO_TARGET_DIR="$out/build"
export RUSTFLAGS="-C instrument-coverage -Z coverage-options=branch"
export LLVM_PROFILE_FILE="$out/profraw/%p-%m.profraw"

# The crates' own tests (unit tests beside the code), in the firmware's
# features. The release profile: the core's calibration and replay tests
# take minutes unoptimised, and the counters are exact at any level.
packages=(-p raim-core -p raim-nav -p raim-proto -p raim-server)
features=(--features raim-server/pf,raim-server/rtcm,raim-nav/rtcm)
cargo +"$NIGHTLY" test --release "${packages[@]}" "${features[@]}" --lib --no-run --message-format=json 2>/dev/null \
    | python3 -c '
import json, sys
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m.get("profile", {}).get("test"):
        print(m["executable"])
' > "$out/binaries.txt"
# Left out of the instrumented run (CI's time; `RAIM_COVERAGE_FULL=1` runs
# them): raim-core's seven brute-force and Monte Carlo tests, about 90 % of
# the instrumented run's test time (~270 s of ~300 s at load 8.5 on 2
# cores). Their code is the shorter tests' code: on 2026-11-29 leaving them
# out lost 1 line and 3 branch outcomes of coverage. They still run,
# uninstrumented, in scripts/test.sh's workspace tests.
skip=()
if [ "${RAIM_COVERAGE_FULL:-0}" != 1 ]; then
    for t in fde_multi random_skies_match_dense_reference skies_without_nominal_bias_match_dense_reference \
        synthetic_constellation_faults_table clean_stream_false_alarms_stay_near_the_budget; do
        skip+=(--skip "$t")
    done
fi
# The proptests' draws from one fixed seed (`PROPTEST_RNG_SEED`), so that
# the figures are the same at every run and a floor is never crossed by a
# draw: with random seeds the branch figures moved by 0.15 points from
# run to run (2026-11-29).
PROPTEST_RNG_SEED="${PROPTEST_RNG_SEED:-37}" \
    cargo +"$NIGHTLY" test --release "${packages[@]}" "${features[@]}" --lib -q -- "${skip[@]}" >"$out/tests.log" 2>&1 || {
    tail -30 "$out/tests.log" >&2
    echo "coverage: the instrumented tests failed (log: $out/tests.log)" >&2
    exit 1
}
"$PROFDATA" merge -sparse "$out"/profraw/*.profraw -o "$out/merged.profdata"
objects=()
while read -r b; do objects+=(-object "$b"); done < "$out/binaries.txt"
# Only the on-device crates' sources, not their tests or dependencies.
ignore='(/\.cargo/registry/|/rustc/|/tests?\.rs$|/tests/|_tests\.rs$|host-tests/|crates/raim-(gnss|recv|qemu|tool)/)'
"$COV" report --summary-only --show-branch-summary "${objects[@]}" \
    -instr-profile="$out/merged.profdata" --ignore-filename-regex="$ignore" > "$out/report.txt"
python3 - "$out/report.txt" "$out/summary.txt" <<'PY'
import re, sys
rows = open(sys.argv[1]).read().splitlines()
# TOTAL, then (count, missed, cover) for regions, functions, lines and
# branches (llvm-cov report --show-branch-summary).
total = next(r for r in rows if r.startswith("TOTAL")).split()
regions = float(total[3].rstrip("%"))
lines = float(total[9].rstrip("%"))
branches = float(total[12].rstrip("%"))
with open(sys.argv[2], "w") as fh:
    fh.write(f"lines {lines:.2f}\nbranches {branches:.2f}\nregions {regions:.2f}\n")
print(f"coverage (raim-core, raim-nav, raim-proto, raim-server; their own tests): lines {lines:.2f} %, branches {branches:.2f} %, regions {regions:.2f} %")
PY
# The product code alone (the test modules inside the sources left out)
# and the justified exceptions of docs/coverage_exceptions.txt, from
# llvm-cov's own per-line and per-branch records.
"$COV" export -format=lcov "${objects[@]}" \
    -instr-profile="$out/merged.profdata" --ignore-filename-regex="$ignore" > "$out/lcov.info"
python3 scripts/coverage_product.py "$out/lcov.info" "$out/summary.txt"
echo "per file: $out/report.txt; uncovered and not justified: $out/unjustified.txt"
if [ "${1:-}" = --check ]; then
    python3 - "$out/summary.txt" docs/coverage_floor.txt <<'PY'
import sys
got = dict(l.split() for l in open(sys.argv[1]) if l.strip())
floor = dict(l.split()[:2] for l in open(sys.argv[2]) if l.strip() and not l.startswith("#"))
bad = [f"{k}: {float(got[k]):.2f} % under the floor {float(v):.2f} %" for k, v in floor.items() if float(got[k]) + 1e-9 < float(v)]
for b in bad:
    print(f"coverage: {b}", file=sys.stderr)
sys.exit(1 if bad else 0)
PY
fi
