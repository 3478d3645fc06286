#!/usr/bin/env bash
# Installs what the project's scripts need and the machine lacks, quietly,
# shared by scripts/main-job.sh and scripts/test.sh (issue 16).
#
#   bash scripts/install-deps.sh main   # the main job: thumbv7em target, qemu-system-arm
#   bash scripts/install-deps.sh test   # the tests: also clippy, rustfmt, gpsd, rtklib and xmllint
#
# Debian/Ubuntu packages are installed with --no-install-recommends (plain
# `apt-get install qemu-system-arm` also pulls the GTK/SDL front ends, about
# 170 packages); apt's output goes to a log that is shown only on failure.
# Prints one line per thing it installs, nothing when all is present.
set -euo pipefail
what="${1:-test}"
case "$what" in main | test) ;; *) echo "usage: $0 [main|test]" >&2; exit 2 ;; esac

if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
    echo "install-deps: rust target thumbv7em-none-eabihf"
    rustup target add thumbv7em-none-eabihf >/dev/null 2>&1
fi
if [ "$what" = test ]; then
    for c in clippy rustfmt; do
        if ! rustup component list --installed 2>/dev/null | grep -q "^$c"; then
            echo "install-deps: rust component $c"
            rustup component add "$c" >/dev/null 2>&1 || true
        fi
    done
fi

# The pinned nightly of scripts/coverage.sh (branch coverage,
# `-Z coverage-options=branch`) and its llvm-tools; the product builds on
# stable. The machine's `nightly` serves when it is the pinned date.
COVERAGE_NIGHTLY="${RAIM_COVERAGE_TOOLCHAIN:-nightly-2026-05-19}"
if [ "$what" = test ]; then
    cov_tc="$COVERAGE_NIGHTLY"
    if ! rustup run "$cov_tc" rustc --version >/dev/null 2>&1 \
        && rustup run nightly rustc --version 2>/dev/null | grep -q "${COVERAGE_NIGHTLY#nightly-}"; then
        cov_tc=nightly
    fi
    if ! rustup run "$cov_tc" rustc --version >/dev/null 2>&1; then
        echo "install-deps: rust toolchain $COVERAGE_NIGHTLY (coverage)"
        rustup toolchain install "$COVERAGE_NIGHTLY" --profile minimal >/dev/null 2>&1
        cov_tc="$COVERAGE_NIGHTLY"
    fi
    if ! rustup component list --installed --toolchain "$cov_tc" 2>/dev/null | grep -q "^llvm-tools"; then
        echo "install-deps: rust component llvm-tools ($cov_tc, coverage)"
        rustup component add llvm-tools --toolchain "$cov_tc" >/dev/null 2>&1
    fi
fi

# Python packages of the tests: pynmea2 (host-tests/tests/nmea_0759.rs
# parses the NMEA writer's sentences with it).
if [ "$what" = test ] && ! python3 -c "import pynmea2" >/dev/null 2>&1; then
    echo "install-deps: pip package pynmea2"
    python3 -m pip install -q pynmea2 >/dev/null 2>&1 \
        || python3 -m pip install -q --break-system-packages pynmea2
fi

# Debian packages, by the command each provides.
pkgs=()
command -v qemu-system-arm >/dev/null || pkgs+=(qemu-system-arm)
if [ "$what" = test ] && ! [ -x /usr/sbin/gpsd ]; then pkgs+=(gpsd); fi
# RTKLIB's pos2kml reads the replay's .pos, xmllint its KML/GPX (cli_tool.rs).
if [ "$what" = test ] && ! command -v pos2kml >/dev/null; then pkgs+=(rtklib); fi
if [ "$what" = test ] && ! command -v xmllint >/dev/null; then pkgs+=(libxml2-utils); fi
# llvm-objdump and llvm-nm read the firmware ELFs (scripts/firmware-evidence.sh).
if [ "$what" = test ] && ! command -v llvm-objdump >/dev/null; then pkgs+=(llvm); fi
if [ "${#pkgs[@]}" -gt 0 ]; then
    echo "install-deps: apt packages ${pkgs[*]} (--no-install-recommends)"
    SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
    log="$(mktemp)"
    if ! { $SUDO apt-get update -qq \
        && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${pkgs[@]}"; } \
        >"$log" 2>&1; then
        cat "$log" >&2
        echo "install-deps: apt-get failed (log above)" >&2
        exit 1
    fi
    rm -f "$log"
fi
