#!/usr/bin/env python3
"""Static analysis of a release firmware ELF from its disassembly
(`llvm-objdump -d`): the call graph, a worst-case stack bound per entry
(main and every exception handler), and the panic paths reachable from
them (issue 37, docs/EVIDENCE.md).

Frames are read from each function's own stack adjustments (push/push.w,
vpush, sub sp by an immediate or by a register loaded with movw/movt); a
call is a bl/blx/b/b.w to a symbol's start (a tail call is counted as a
call, which can only over-estimate). Indirect calls (blx rN) and
recursion cannot be bounded from the graph: they are listed, and each
must be bounded by hand in docs/EVIDENCE.md.

Usage:
  firmware_callgraph.py ELF [--json OUT] [--entry NAME ...]
Prints a report; exit 0. The checks against limits are in
scripts/firmware-evidence.sh.
"""
import collections
import json
import re
import subprocess
import sys

HDR = re.compile(r"^([0-9a-f]+) <(.+)>:$")
INS = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$")
TARGET = re.compile(r"<([^>+]+)(\+0x[0-9a-f]+)?>")
REGLIST = re.compile(r"\{([^}]*)\}")
IMM = re.compile(r"#(-?(?:0x[0-9a-f]+|\d+))")
HASH = re.compile(r"17h[0-9a-f]{16}E$")

# An exception's hardware frame with the FPU context (lazy stacking
# reserves it): 26 words (ARMv7-M ARM B1.5.7).
EXCEPTION_FRAME_BYTES = 104

PANIC_MARKERS = (
    "panicking",
    "panic_already",
    "slice_index_fail",
    "unwrap_failed",
    "expect_failed",
    "rust_begin_unwind",
)


def demangle_hashless(name):
    """The legacy-mangled name without its hash (stable across builds)."""
    return HASH.sub("E", name)


def imm(text):
    m = IMM.search(text)
    if not m:
        return None
    v = m.group(1)
    return int(v, 16) if v.startswith("0x") else int(v)


def reg_count(text, width):
    m = REGLIST.search(text)
    if not m:
        return 0
    n = 0
    for part in m.group(1).split(","):
        part = part.strip()
        if "-" in part:
            a, b = part.split("-")
            n += int(b.strip()[1:]) - int(a.strip()[1:]) + 1
        elif part:
            n += 1
    return n * width


def parse(dis_lines):
    funcs = collections.OrderedDict()
    cur = None
    in_data = False
    for line in dis_lines:
        m = HDR.match(line)
        if m:
            name = m.group(2)
            if name.startswith("$"):
                in_data = name == "$d"
                continue
            cur = name
            in_data = False
            funcs[cur] = {"ins": [], "addr": int(m.group(1), 16)}
            continue
        m = INS.match(line)
        if m and cur and not in_data:
            funcs[cur]["ins"].append((m.group(2), m.group(3)))
    return funcs


def elf_reader(path):
    """A word reader over the ELF32's loaded sections (for vtables)."""
    import struct

    data = open(path, "rb").read()
    shoff = struct.unpack_from("<I", data, 0x20)[0]
    shentsize, shnum = struct.unpack_from("<HH", data, 0x2E)
    sections = []
    for k in range(shnum):
        off = shoff + k * shentsize
        _n, typ, _fl, addr, offset, size = struct.unpack_from("<IIIIII", data, off)
        if typ == 1 and addr:  # PROGBITS with an address
            sections.append((addr, offset, size))

    def word(addr):
        for a, o, sz in sections:
            if a <= addr and addr + 4 <= a + sz:
                return struct.unpack_from("<I", data, o + addr - a)[0]
        return None

    return word


# Functions whose stack adjustment is by a register the analysis could not
# resolve (an alloca): their frames are unknown and listed.
dynamic = set()


def analyse(funcs, word=None, starts=None):
    frame = {}
    calls = collections.defaultdict(set)
    indirect = {}
    resolved = {}
    dynamic.clear()
    for f, d in funcs.items():
        size = 0
        regs = {}
        alt = {}
        slots = {}
        n_indirect = 0
        for op, args in d["ins"]:
            base = op.split(".")[0]
            if base == "push":
                size += reg_count(args, 4)
            elif base == "vpush":
                size += reg_count(args, 8 if "d" in args else 4)
            elif base in ("movw", "mov") and "#" in args:
                r = args.split(",")[0].strip()
                regs[r] = imm(args) or 0
                alt.pop(r, None)
            elif op.startswith("mov") and "#" not in args and "," in args:
                # mov{cond} rX, rY: rX may hold rY's value (a conditional
                # move keeps both candidates).
                dst, src = (a.strip() for a in args.split(",")[:2])
                if src in regs:
                    if op in ("mov", "mov.w"):
                        regs[dst] = regs[src]
                        alt.pop(dst, None)
                    else:
                        alt.setdefault(dst, set()).add(regs[src])
            elif base == "movt" and "#" in args:
                r = args.split(",")[0].strip()
                regs[r] = (regs.get(r, 0) & 0xFFFF) | ((imm(args) or 0) << 16)
            elif base in ("sub", "subw") and args.replace(" ", "").startswith("sp,"):
                parts = [p.strip() for p in args.split(",")]
                last = parts[-1]
                if last.startswith("#"):
                    size += imm(last) or 0
                elif last in regs:
                    size += regs[last]
                else:
                    dynamic.add(f)
            if base == "ldr" and "[" in args and word is not None:
                # ldr rY, [rX, #off] with rX a constant: a vtable slot.
                m = re.match(r"\s*(r\d+|lr|r1[0-2]),\s*\[(r\d+|r1[0-2])(?:,\s*#(\d+))?\]", args)
                if m and m.group(2) in regs:
                    w = word(regs[m.group(2)] + int(m.group(3) or 0))
                    slots[m.group(1)] = w
                elif m:
                    slots.pop(m.group(1), None)
            if base in ("bl", "blx", "b") or op in ("b.w",):
                if base == "blx" and not TARGET.search(args):
                    r = args.strip()
                    cands = {slots.get(r), regs.get(r)} | alt.get(r, set())
                    hit = {starts[w & ~1] for w in cands if w is not None and starts and (w & ~1) in starts}
                    if hit:
                        for h in hit:
                            calls[f].add(h)
                            resolved.setdefault(f, set()).add(h)
                    else:
                        n_indirect += 1
                    continue
                m = TARGET.search(args)
                if m and m.group(2) is None and m.group(1) != f and m.group(1) in funcs:
                    calls[f].add(m.group(1))
        frame[f] = size
        if n_indirect:
            indirect[f] = n_indirect
    return frame, calls, indirect, resolved


def worst(entry, frame, calls):
    """Worst-case stack from `entry` and its path; cycles are cut and
    reported (recursion must be bounded by hand)."""
    memo = {}
    cycles = set()
    sys.setrecursionlimit(100000)

    def go(f, stack):
        if f in memo:
            return memo[f]
        if f in stack:
            cycles.add(f)
            return (0, [])
        stack.add(f)
        best = (0, [])
        for c in sorted(calls.get(f, ())):
            s = go(c, stack)
            if s[0] > best[0]:
                best = s
        stack.discard(f)
        r = (frame.get(f, 0) + best[0], [f] + best[1])
        memo[f] = r
        return r

    total, path = go(entry, set())
    return total, path, cycles


def reachable(entry, calls):
    seen = set()
    todo = [entry]
    parent = {entry: None}
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        for c in calls.get(f, ()):
            if c not in parent:
                parent[c] = f
            todo.append(c)
    return seen, parent


def is_panic(name):
    return any(m in name for m in PANIC_MARKERS)


def stack_region(elf):
    """The stack region of a build: from the top of RAM (_stack_start)
    down to the 1 KiB MPU guard above the statics (firmware/src/guard.rs;
    scripts/firmware-memory.sh computes the same)."""
    syms = {}
    out = subprocess.run(["llvm-nm", elf], check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] in ("__sheap", "_stack_start"):
            syms[parts[2]] = int(parts[0], 16)
    if len(syms) != 2:
        return None
    guard = (syms["__sheap"] + 1023) // 1024 * 1024
    return syms["_stack_start"] - guard - 1024


def main():
    args = sys.argv[1:]
    if not args:
        print(__doc__)
        return 2
    elf = args[0]
    out_json = None
    entries = []
    i = 1
    while i < len(args):
        if args[i] == "--json":
            out_json = args[i + 1]
            i += 2
        elif args[i] == "--entry":
            entries.append(args[i + 1])
            i += 2
        else:
            print(f"unknown argument {args[i]}", file=sys.stderr)
            return 2
    dis = subprocess.run(
        ["llvm-objdump", "-d", "--no-show-raw-insn", elf],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.splitlines()
    funcs = parse(dis)
    starts = {d["addr"]: f for f, d in funcs.items()}
    frame, calls, indirect, resolved = analyse(funcs, elf_reader(elf), starts)
    handlers = [
        f
        for f in (
            "SysTick",
            "UsageFault",
            "NonMaskableInt",
            "HardFault",
            "_HardFault",
            "MemoryManagement",
            "BusFault",
            "SVCall",
            "PendSV",
            "DefaultHandler",
            "DefaultHandler_",
        )
        if f in funcs
    ]
    # Device interrupt handlers: unmangled names that are not runtime or
    # compiler-builtins symbols.
    for f in funcs:
        if (
            re.fullmatch(r"[A-Z][A-Z0-9_]+", f)
            and f not in handlers
            and f not in ("__stext",)
        ):
            handlers.append(f)
    if not entries:
        entries = ["main"] + handlers
    report = {"elf": elf, "entries": {}, "indirect_calls": {}, "panic_paths": {}}
    for e in entries:
        if e not in funcs:
            print(f"entry {e} not in the ELF", file=sys.stderr)
            return 2
        total, path, cycles = worst(e, frame, calls)
        seen, parent = reachable(e, calls)
        ind = sorted(f for f in seen if f in indirect)
        panics = sorted(f for f in seen if is_panic(f))
        # For each panic function reached, the non-panic functions that
        # call it directly: the panic sites.
        sites = sorted(
            {
                demangle_hashless(f)
                for f in seen
                if not is_panic(f) and any(is_panic(c) for c in calls.get(f, ()))
            }
        )
        res = sorted(
            f"{demangle_hashless(a)} -> {demangle_hashless(b)}"
            for a in seen
            for b in resolved.get(a, ())
        )
        report["entries"][e] = {
            "dynamic_frames": sorted(demangle_hashless(f) for f in seen if f in dynamic),
            "resolved_indirect": res,
            "stack_bytes": total,
            "path": [demangle_hashless(p) for p in path],
            "recursion": sorted(demangle_hashless(c) for c in cycles),
            "indirect": [demangle_hashless(f) for f in ind],
            "panic_functions": [demangle_hashless(p) for p in panics],
            "panic_sites": sites,
        }
    handler_sum = sum(
        report["entries"][h]["stack_bytes"] + EXCEPTION_FRAME_BYTES
        for h in entries
        if h != "main" and h in report["entries"]
    )
    report["main_plus_all_handlers_bytes"] = (
        report["entries"].get("main", {}).get("stack_bytes", 0) + handler_sum
    )
    # Handlers run at one priority (cortex-m-rt's reset value) and do not
    # preempt each other; the faults (HardFault, NMI) end in a reset. The
    # bound is main plus the deepest single handler and its frame.
    deepest_handler = max(
        (
            report["entries"][h]["stack_bytes"] + EXCEPTION_FRAME_BYTES
            for h in entries
            if h != "main" and h in report["entries"]
        ),
        default=0,
    )
    report["bound_bytes"] = (
        report["entries"].get("main", {}).get("stack_bytes", 0) + deepest_handler
    )
    region = stack_region(elf)
    report["stack_region_bytes"] = region
    for e, r in report["entries"].items():
        print(f"entry {e}: worst-case stack {r['stack_bytes']} B")
        print("  deepest path: " + " -> ".join(p[-60:] for p in r["path"][:12]))
        if r["recursion"]:
            print(f"  recursion (bounded by hand): {r['recursion']}")
        if r["dynamic_frames"]:
            print(f"  frames sized at run time (unbounded here): {r['dynamic_frames']}")
        if r["indirect"]:
            print(f"  unresolved indirect calls in: {r['indirect']}")
        for x in r["resolved_indirect"]:
            print(f"  indirect call through a constant vtable: {x[-140:]}")
        print(f"  panic sites reachable: {len(r['panic_sites'])}")
    print(
        f"bound: main plus the deepest handler and its exception frame: "
        f"{report['bound_bytes']} B; stack region {region} B"
    )
    print(
        f"main plus every handler nested once (+{EXCEPTION_FRAME_BYTES} B each): "
        f"{report['main_plus_all_handlers_bytes']} B"
    )
    if out_json:
        with open(out_json, "w") as fh:
            json.dump(report, fh, indent=1, sort_keys=True)
            fh.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
