#!/usr/bin/env bash
# Static evidence from the release firmware ELFs (issue 37): the worst-case
# stack of every entry (main and each exception handler) from the call
# graph and the per-function frames of the disassembly
# (scripts/firmware_callgraph.py), checked against each build's stack
# region; and the panic sites reachable from every entry, each of which
# must be listed in docs/panic_allowlist.toml (no entry for raim-core: a
# panic path in the core fails the check), with no stale entry. Run from
# the repository root after scripts/test.sh's firmware builds. Needs
# llvm-objdump and llvm-nm (the `llvm` package, installed by
# scripts/install-deps.sh test).
#
# Fails when a bound exceeds its build's stack region, when a frame is
# sized at run time, or when an indirect call is left unresolved: each of
# those must be removed or bounded by hand in docs/EVIDENCE.md first.
set -euo pipefail
cd "$(dirname "$0")/.."
# scripts/test.sh keeps each build's ELF in firmware/target/elf/ (one
# shared target directory); a build by hand with the per-configuration
# target directories of scripts/firmware-memory.sh's header also works.
ELF=thumbv7em-none-eabihf/release/raim-firmware
pick() { if [ -f "firmware/target/elf/$1" ]; then echo "firmware/target/elf/$1"; else echo "$2"; fi; }
status=0
JSON_DIR=$(mktemp -d)
for build in "QEMU mps2-an386, default:$(pick qemu "firmware/target/$ELF")" \
             "QEMU mps2-an386, snapshot:$(pick snapshot "firmware/target/snapshot/$ELF")" \
             "STM32F4 (hardware layout):$(pick stm32f4-hw "firmware/target/stm32f4-hw/$ELF")" \
             "STM32F4 (netduinoplus2 layout):$(pick stm32f4-netduinoplus2 "firmware/target/stm32f4/$ELF")" \
             "STM32F4 with the stream (hardware layout):$(pick stm32f4-stream-hw "firmware/target/stm32f4-stream-hw/$ELF")"; do
    name=${build%%:*}
    elf=${build#*:}
    [ -f "$elf" ] || { echo "== $name: no $elf (build it first)"; status=1; continue; }
    echo "== $name"
    json="$JSON_DIR/$(echo "$name" | tr -c 'A-Za-z0-9' '_').json"
    python3 scripts/firmware_callgraph.py "$elf" --json "$json" | grep -v "deepest path"
    python3 - "$json" "$name" <<'PY' || status=1
import json, sys
r = json.load(open(sys.argv[1]))
name = sys.argv[2]
bad = []
if r["stack_region_bytes"] is None or r["bound_bytes"] > r["stack_region_bytes"]:
    bad.append(f"stack bound {r['bound_bytes']} B over the region {r['stack_region_bytes']} B")
for e, x in r["entries"].items():
    if x["dynamic_frames"]:
        bad.append(f"{e}: frames sized at run time {x['dynamic_frames']}")
    if x["indirect"]:
        bad.append(f"{e}: unresolved indirect calls in {x['indirect']}")
for b in bad:
    print(f"  FAIL ({name}): {b}")
sys.exit(1 if bad else 0)
PY
done
# Panic sites: every one reachable in any build must be listed in
# docs/panic_allowlist.toml, every entry there must match a site, and
# every entry must be off the input path (kind logger, boot or hook): a
# site on the input path cannot be allowed, it must be removed.
python3 - "$JSON_DIR" docs/panic_allowlist.toml <<'PY' || status=1
import glob, json, sys, tomllib
reports = [json.load(open(p)) for p in sorted(glob.glob(sys.argv[1] + "/*.json"))]
allow = tomllib.load(open(sys.argv[2], "rb"))["site"]
sites = {}
for r in reports:
    for e, x in r["entries"].items():
        for s in x["panic_sites"]:
            sites.setdefault(s, set()).add(e)
unlisted = sorted(s for s in sites if not any(a["symbol"] in s for a in allow))
stale = [a["symbol"] for a in allow if not any(a["symbol"] in s for s in sites)]
KINDS = ("logger", "boot", "hook")
bad_kind = [a for a in allow if a.get("kind") not in KINDS]
ok = not (unlisted or stale or bad_kind)
print(f"== panic sites: {len(sites)} reachable across the builds"
      + (", each allowed in docs/panic_allowlist.toml, none on the input path" if ok else ""))
for a in bad_kind:
    print(f"  FAIL: docs/panic_allowlist.toml entry {a['symbol']} of kind {a.get('kind')!r}: only {', '.join(KINDS)} may be allowed")
for s in unlisted:
    print(f"  FAIL: panic site not in docs/panic_allowlist.toml: {s} (from {sorted(sites[s])})")
for a in stale:
    print(f"  FAIL: docs/panic_allowlist.toml entry matches no panic site (remove it): {a}")
sys.exit(1 if unlisted or stale or bad_kind else 0)
PY
rm -rf "$JSON_DIR"
exit $status
