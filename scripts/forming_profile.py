#!/usr/bin/env python3
"""Where a stream epoch's forming spends its instructions on the M4
(BENCHMARKS.md "Forming by sum formulas").

Reads a QEMU log of `-d exec,nochain,in_asm` (each translated block's
instructions from its `IN:` listing, each execution from its `Trace` line)
of a firmware run, takes the last call of the receiver's `form` that ran
more than 300,000 instructions (the call from its entry block to its last
block before the next entry), and charges every block of it to the
nearest raim function executed before it: the soft-float (compiler
builtins) and libm routines to their raim caller. Prints the charged
instructions per function, then the libm routines per raim caller.

    # a wrapper that adds the trace to the firmware's QEMU:
    mkdir -p /tmp/qwrap && printf '#!/bin/sh\\nexec /usr/bin/qemu-system-arm "$@" -d exec,nochain,in_asm -D /tmp/trace.$$.log\\n' > /tmp/qwrap/qemu-system-arm
    chmod +x /tmp/qwrap/qemu-system-arm
    PATH=/tmp/qwrap:$PATH RAIM_FIRMWARE_ELF_STREAM=<elf> cargo test --release -p host-tests \\
        --test qemu_rtcm qemu_rtcm_stream_epoch_cost -- --nocapture
    python3 scripts/forming_profile.py /tmp/trace.<pid>.log <elf>

The log of the GMSD7 cost test is about 2.2 GB.
"""
import collections
import re
import subprocess
import sys

FORM = "receiver27StreamReceiver$LT$_$C$_$GT$4form17"
TRACE = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/[^\]]*\] ?(.*)$")


def main(log, elf):
    nm = subprocess.run(["nm", elf], capture_output=True, text=True, check=True).stdout
    starts = [int(l.split()[0], 16) & ~1 for l in nm.splitlines() if FORM in l]
    if len(starts) != 1:
        sys.exit(f"{elf}: {len(starts)} symbols of the receiver's form")
    form_start = starts[0]
    ninsn, seq, cur = {}, [], None
    with open(log, errors="replace") as f:
        for line in f:
            if line.startswith("Trace"):
                m = TRACE.match(line)
                if m:
                    seq.append((int(m.group(1), 16), m.group(2).strip()))
                cur = None
            elif line.startswith("0x"):
                addr = int(line.split(":")[0], 16)
                if cur is None:
                    cur = addr
                    ninsn[cur] = 0
                ninsn[cur] += 1
            else:
                cur = None
    entries = [i for i, (pc, _) in enumerate(seq) if pc == form_start] + [len(seq)]
    window = None
    for a, b in zip(entries, entries[1:]):
        last = max(i for i in range(a, b) if FORM in seq[i][1])
        n = sum(ninsn.get(pc, 0) for pc, _ in seq[a : last + 1])
        if n > 300_000:
            window = (a, last)
    if window is None:
        sys.exit("no forming of more than 300,000 instructions in the log")
    near, libm = collections.Counter(), collections.Counter()
    last_raim, last_libm = "?", None
    for pc, s in seq[window[0] : window[1] + 1]:
        n = ninsn.get(pc, 0)
        if "raim_" in s and "libm" not in s:
            last_raim, last_libm = s, None
        near[last_raim] += n
        if "libm" in s:
            last_libm = s
        if last_libm and "raim_" not in s:
            libm[(last_raim, last_libm)] += n
    total = sum(near.values())
    name = lambda s: re.sub(r"17h[0-9a-f]{16}E$", "", s)
    print(f"forming: {total} instructions")
    for s, c in near.most_common(40):
        print(f"{c:10d} {100 * c / total:5.1f}%  {name(s)}")
    print("libm routines by raim caller:")
    for (r, l), c in libm.most_common(25):
        print(f"{c:10d}  {name(r)} <- {name(l)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
