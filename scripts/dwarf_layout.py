#!/usr/bin/env python3
"""The members of a struct in a firmware ELF, from its DWARF (the release
profile keeps `debug = 2`): each member's offset span, padding included,
largest first by offset order. Used to break a static down when
`llvm-nm --size-sort` shows only the static's total (docs/FLASH.md
"STM32F4: the stream beside ARAIM and the PF").

Usage: dwarf_layout.py ELF STRUCT_NAME [MIN_BYTES]
STRUCT_NAME is the DWARF name as llvm-dwarfdump --name matches it, e.g.
`Server`, `StreamState`, `StreamReceiver<32, 256>`; members of fewer than
MIN_BYTES (default 0) are left out.
"""
import re
import subprocess
import sys

elf, name = sys.argv[1], sys.argv[2]
minb = int(sys.argv[3]) if len(sys.argv) > 3 else 0
out = subprocess.run(["llvm-dwarfdump", f"--name={name}", "--show-children", elf],
                     capture_output=True, text=True).stdout.splitlines()
def indent(l):
    body = l.split(":", 1)[1]
    return len(body) - len(body.lstrip())
size=None; start=None
for i,l in enumerate(out):
    if "DW_TAG_structure_type" in l:
        j=i+1; s=None
        while j<len(out) and not re.match(r"^0x[0-9a-f]+:", out[j]):
            m=re.search(r"DW_AT_byte_size\s+\((0x[0-9a-f]+)\)", out[j])
            if m: s=int(m.group(1),16)
            j+=1
        if s: size=s; start=j; break
members=[]; mind=None; cur=None
for l in out[start:]:
    if re.match(r"^0x[0-9a-f]+:", l):
        ind=indent(l)
        if "DW_TAG_structure_type" in l and mind is not None and ind < mind: break
        if "DW_TAG_member" in l and (mind is None or ind==mind):
            mind=ind; cur={}; members.append(cur)
        else:
            cur=None
    elif cur is not None:
        m=re.search(r'DW_AT_name\s+\("(.+)"\)', l)
        if m and "name" not in cur: cur["name"]=m.group(1)
        m=re.search(r'DW_AT_type\s+\(0x[0-9a-f]+ "(.+)"\)', l)
        if m and "type" not in cur: cur["type"]=m.group(1)
        m=re.search(r"DW_AT_data_member_location\s+\((0x[0-9a-f]+)\)", l)
        if m: cur["off"]=int(m.group(1),16)
members=[m for m in members if "off" in m]; members.sort(key=lambda m:m["off"])
print(f"{name}: {size} B")
for a,b in zip(members, members[1:]+[{"off":size}]):
    span=b["off"]-a["off"]
    if span>=minb: print(f"  {span:8d} B  {a.get('name')}: {a.get('type','?')}")
