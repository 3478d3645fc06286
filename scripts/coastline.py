#!/usr/bin/env python3
"""Writes crates/raim-availability/data/coastline_ne110m.bin, the coastlines
drawn on the availability maps (docs/AVAILABILITY.md "Maps").

Source: Natural Earth's 1:110m coastline (public domain,
https://www.naturalearthdata.com/about/terms-of-use/), as packaged in the
crates.io crate `plotine` 0.5.2 (MIT licence), file
`src/geo/data/coastline.bin`: magic 0x50474C43 ("CGLP"), version 1, a point count n, then
n little-endian f32 pairs (longitude, latitude in degrees), NaN pairs
between lines. This script fetches the crate with cargo's ordinary client
(`cargo info plotine@0.5.2` puts the .crate in cargo's registry cache),
reads the file out of the .crate, checks its SHA-256, and writes every line
unsimplified, rounded to 0.01 degree, as little-endian i16 pairs
(longitude, latitude in hundredths of a degree) with (-32768, -32768)
between two lines; repeated points after rounding are dropped, and lines
left with fewer than two points.

Usage: python3 scripts/coastline.py [--check]
"""
import glob
import hashlib
import math
import os
import struct
import subprocess
import sys
import tarfile

CRATE, VERSION = "plotine", "0.5.2"
MEMBER = f"{CRATE}-{VERSION}/src/geo/data/coastline.bin"
SHA256 = "f5440285c6aba7ef22893b2dbaa3e293f83b952cf6b2d19566b42a7fe72cb751"
OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "raim-availability", "data", "coastline_ne110m.bin")


def crate_file():
    home = os.environ.get("CARGO_HOME", os.path.expanduser("~/.cargo"))
    pattern = os.path.join(home, "registry", "cache", "*", f"{CRATE}-{VERSION}.crate")
    found = glob.glob(pattern)
    if not found:
        subprocess.run(["cargo", "info", f"{CRATE}@{VERSION}"], check=True, stdout=subprocess.DEVNULL)
        found = glob.glob(pattern)
    if not found:
        sys.exit(f"coastline.py: {CRATE} {VERSION} not in cargo's registry cache ({pattern})")
    return found[0]


def main():
    check = sys.argv[1:] == ["--check"]
    with tarfile.open(crate_file(), "r:gz") as t:
        data = t.extractfile(MEMBER).read()
    digest = hashlib.sha256(data).hexdigest()
    if digest != SHA256:
        sys.exit(f"coastline.py: {MEMBER} has SHA-256 {digest}, expected {SHA256}")
    magic, version, n = struct.unpack_from("<III", data, 0)
    if magic != 0x5047_4C43:  # "CGLP" as plotine writes it
        sys.exit(f"coastline.py: bad magic {magic:#x}")
    if version != 1 or len(data) < 12 + 8 * n:
        sys.exit(f"coastline.py: version {version}, {len(data)} bytes for {n} points")
    lines, line = [], []
    for k in range(n):
        lon, lat = struct.unpack_from("<ff", data, 12 + 8 * k)
        if math.isnan(lon) or math.isnan(lat):
            lines.append(line)
            line = []
            continue
        p = (round(lon * 100), round(lat * 100))
        if not (-18000 <= p[0] <= 18000 and -9000 <= p[1] <= 9000):
            sys.exit(f"coastline.py: point {k} ({lon}, {lat}) out of range")
        if not line or line[-1] != p:
            line.append(p)
    lines.append(line)
    lines = [l for l in lines if len(l) >= 2]
    out = bytearray()
    for i, l in enumerate(lines):
        if i:
            out += struct.pack("<hh", -32768, -32768)
        for x, y in l:
            out += struct.pack("<hh", x, y)
    print(f"{MEMBER}: SHA-256 {digest}, {n} records; {len(lines)} lines, "
          f"{sum(map(len, lines))} points, {len(out)} bytes")
    if check:
        with open(OUT, "rb") as f:
            if f.read() != bytes(out):
                sys.exit(f"coastline.py: {OUT} differs from what the source gives")
        return
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main()
