#!/usr/bin/env python3
"""Plots correct identification against the smallest fault size for t = 1, 2, 3
(today's FDE dashed, the reconstruction solid) from the Monte Carlo's CSV, as
a dependency-free SVG (docs/MULTIFAULT.md):

    cargo run --release -p raim-core --example multifault_mc -- 30000 11 1000
    python3 tools/plot_multifault_mc.py target/multifault_mc.csv > docs/multifault_mc.svg
"""
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))
W, H, L, B, T, R = 640, 400, 60, 50, 30, 150
colors = {"1": "#1f77b4", "2": "#d62728", "3": "#2ca02c"}
xmax = max(float(r["bin_hi_m"]) for r in rows)


def px(x):
    return L + (W - L - R) * x / xmax


def py(y):
    return T + (H - T - B) * (1 - y)


out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2 - 60}" y="18">Correct identification vs smallest fault size</text>']
for k in range(0, 11, 2):
    y = k / 10
    out.append(f'<line x1="{L}" y1="{py(y)}" x2="{W-R}" y2="{py(y)}" stroke="#ddd"/>')
    out.append(f'<text x="{L-30}" y="{py(y)+4}">{y:.1f}</text>')
for x in range(0, int(xmax) + 1, 10):
    out.append(f'<text x="{px(x)-8}" y="{H-B+18}">{x}</text>')
out.append(f'<text x="{(W-R)/2}" y="{H-12}">smallest fault (m = sigma)</text>')
out.append(f'<line x1="{L}" y1="{py(0)}" x2="{W-R}" y2="{py(0)}" stroke="black"/>')
out.append(f'<line x1="{L}" y1="{py(0)}" x2="{L}" y2="{py(1)}" stroke="black"/>')
ly = T + 10
for method, dash in (("sequential", "6,4"), ("reconstruction", "")):
    for t in ("1", "2", "3"):
        pts = [((float(r["bin_lo_m"]) + float(r["bin_hi_m"])) / 2,
                int(r["correct"]) / max(1, int(r["draws"])))
               for r in rows if r["method"] == method and r["t"] == t]
        path = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in pts)
        style = f'stroke-dasharray="{dash}"' if dash else ""
        out.append(f'<polyline points="{path}" fill="none" stroke="{colors[t]}" stroke-width="2" {style}/>')
        out.append(f'<line x1="{W-R+10}" y1="{ly}" x2="{W-R+35}" y2="{ly}" stroke="{colors[t]}" stroke-width="2" {style}/>')
        out.append(f'<text x="{W-R+40}" y="{ly+4}">{method[:5]}. t={t}</text>')
        ly += 18
out.append("</svg>")
print("\n".join(out))
