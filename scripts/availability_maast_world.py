#!/usr/bin/env python3
"""Our engine against the ADD v4.2 reference implementation on every
user-epoch of the MAAST world grid (scripts/availability_maast_world.sh).

Reads WORK/ours.csv (examples/dump_sky.rs: our VPL, HPL, EMT, sigma_v,acc,
availability and PL roots per user-epoch) and WORK/ref_<variant>_lat*.csv
(scripts/octave/availability_maast_world.m), and prints in Markdown:
coverage (cos-latitude weights) at 99.5 % and at the second level from
each side's PLs under each availability rule, the per-user 99.5th-percentile
VPL and HPL differences, the worst users, and for the users beyond the
targets (coverage within 0.5 points, VPL percentile within 1 %) which
variant of the reference brings them within. The percentile and the
coverage are defined as the engine's (crates/raim-availability/src/engine.rs
`percentile`: sorted[ceil(p n) - 1]; output.rs `coverage`); that our own
coverage computed here equals the engine's summary is checked (the
`--summary` file, default the committed one).

Usage: availability_maast_world.py WORK_DIR [--summary FILE] [--galtable USERS_CSV]
"""
import argparse
import csv
import glob
import json
import math
import os

P = 0.995
LEVELS = (0.995, 0.99)
VAL, HAL, EMT_MAX, SIGMA_ACC_MAX = 35.0, 40.0, 15.0, 1.87
VARIANTS = ("published", "all", "v3", "refmodel")

ap = argparse.ArgumentParser()
ap.add_argument("work")
here = os.path.dirname(os.path.abspath(__file__))
docs = os.path.join(here, "..", "docs", "availability")
ap.add_argument("--summary", default=os.path.join(docs, "availability_maast_g24e24.summary.json"))
ap.add_argument("--galtable", default=os.path.join(docs, "availability_maast_g24e24_galtable.users.csv"))
args = ap.parse_args()


def pct(v):
    """The engine's percentile: sorted[ceil(p n) - 1] (+inf counts)."""
    v = sorted(v)
    k = min(max(math.ceil(P * len(v)), 1), len(v))
    return v[k - 1]


ours = {}
users = {}
for r in csv.DictReader(open(os.path.join(args.work, "ours.csv"))):
    c = int(r["case"])
    u = (float(r["lat_deg"]), float(r["lon_deg"]))
    ours[c] = {k: float(r[k]) for k in ("vpl_m", "hpl_m", "emt_m", "sigma_v_acc_m", "vpl_root_m", "hpl_root_m", "modes")}
    ours[c]["available"] = r["available"] == "1"
    users.setdefault(u, []).append(c)

ref = {}
part = {}
for v in VARIANTS:
    files = glob.glob(os.path.join(args.work, f"ref_{v}_lat*.csv"))
    rows = {}
    for f in files:
        for r in csv.DictReader(open(f)):
            rows[int(r["case"])] = (float(r["modes"]), float(r["vpl_m"]), float(r["hpl_m"]))
    if rows:
        missing = len(ours) - len(rows)
        if missing:
            print(f"variant {v}: {missing} of {len(ours)} user-epochs missing (run incomplete): "
                  "no coverage; per-user figures for the users it covers")
            part[v] = rows
        else:
            ref[v] = rows
inf = float("inf")


def weight(u):
    return max(math.cos(math.radians(u[0])), 0.0)


def coverage(avail, level):
    tot = sum(weight(u) for u in users)
    return sum(weight(u) for u in users if avail[u] >= level) / tot


def mean_avail(avail):
    tot = sum(weight(u) for u in users)
    return sum(weight(u) * avail[u] for u in users) / tot


def availability(pred):
    return {u: sum(1 for c in cs if pred(c)) / len(cs) for u, cs in users.items()}


def our_emt_ok(c):
    return ours[c]["emt_m"] <= EMT_MAX and ours[c]["sigma_v_acc_m"] <= SIGMA_ACC_MAX


def get(v, c, i):
    x = (ref[v] if v in ref else part[v]).get(c)
    return inf if x is None or math.isnan(x[i]) else x[i]


rules = [
    ("ours", "engine: VPL <= 35, HPL <= 40, EMT <= 15, sigma_v,acc <= 1.87 m", lambda c: ours[c]["available"]),
    ("ours", "the reference's rule: VPL < 35 and HPL < 40 m", lambda c: ours[c]["vpl_m"] < VAL and ours[c]["hpl_m"] < HAL),
]
names = {
    "published": "reference as published",
    "all": "reference, every single-event mode monitored",
    "v3": "reference's functions per ADD v3.0 (P_unmon, roots), modnormcdf = normal cdf",
    "refmodel": "reference as published, its own error model (Galileo table)",
}
for v in ref:
    rules.append((names[v], "its rule: VPL < 35 and HPL < 40 m", lambda c, v=v: get(v, c, 1) < VAL and get(v, c, 2) < HAL))
    rules.append((names[v], "its rule with our EMT <= 15 m and sigma_v,acc <= 1.87 m",
                  lambda c, v=v: get(v, c, 1) < VAL and get(v, c, 2) < HAL and our_emt_ok(c)))

summary = json.load(open(args.summary))
engine_cov = {e["level"]: e["coverage"] for e in summary["coverage"]}
print(f"users: {len(users)}, user-epochs: {len(ours)}; reference variants complete: {', '.join(ref) or 'none'}")
print()
print("| PLs | availability rule | coverage at 99.5 % | at 99 % | mean availability (area-weighted) |")
print("| --- | --- | ---: | ---: | ---: |")
avails = {}
for who, rule, pred in rules:
    a = availability(pred)
    avails[(who, rule)] = a
    cov = [coverage(a, lv) for lv in LEVELS]
    print(f"| {who} | {rule} | {100 * cov[0]:.2f} % | {100 * cov[1]:.2f} % | {100 * mean_avail(a):.3f} % |")
ours_cov = [coverage(avails[rules[0][:2]], lv) for lv in LEVELS]
for lv, cv in zip(LEVELS, ours_cov):
    assert abs(cv - engine_cov[lv]) < 1e-12, f"our coverage here {cv} != the engine's summary {engine_cov[lv]}"
print()
print(f"(our coverage computed here equals the engine's summary, {os.path.basename(args.summary)}: "
      f"{100 * engine_cov[0.995]:.2f} % and {100 * engine_cov[0.99]:.2f} %)")
# Each reference row against ours under the same rule: its rule against
# our PLs judged by its rule, its rule with our EMT and sigma_v,acc
# against the engine's decision.
for k, (who, rule, _) in enumerate(rules[2:]):
    base_key = rules[1][:2] if k % 2 == 0 else rules[0][:2]
    base = avails[base_key]
    a = avails[(who, rule)]
    d = [100 * (coverage(a, lv) - coverage(base, lv)) for lv in LEVELS]
    print(f"- {who}, {rule}; against ours, {base_key[1]}: {d[0]:+.2f} points at 99.5 %, {d[1]:+.2f} at 99 %; "
          f"users with another availability: {sum(1 for u in users if a[u] != base[u])}, "
          f"across 99.5 %: {sum(1 for u in users if (a[u] >= 0.995) != (base[u] >= 0.995))}")

# What our EMT and sigma_v,acc limits take from the reference's rule.
if "published" in ref:
    a_no = avails[(names["published"], "its rule: VPL < 35 and HPL < 40 m")]
    a_with = avails[(names["published"], "its rule with our EMT <= 15 m and sigma_v,acc <= 1.87 m")]
    lost = [u for u in users if a_no[u] >= 0.995 > a_with[u]]
    lats = {}
    for u in lost:
        lats[abs(u[0])] = lats.get(abs(u[0]), 0) + 1
    emt = sum(1 for u in users for c in users[u] if ours[c]["emt_m"] > EMT_MAX)
    sig = sum(1 for u in users for c in users[u] if ours[c]["sigma_v_acc_m"] > SIGMA_ACC_MAX)
    print(f"- users at 99.5 % under the reference's rule and below it once our EMT and sigma_v,acc limits are "
          f"added: {len(lost)}, by |latitude|: " + ", ".join(f"{k:.0f} deg: {n}" for k, n in sorted(lats.items()))
          + f"; user-epochs with our EMT above 15 m: {emt}, with sigma_v,acc above 1.87 m: {sig}")

# Per-user 99.5th-percentile PLs.
our_pct = {u: (pct([ours[c]["vpl_m"] for c in cs]), pct([ours[c]["hpl_m"] for c in cs])) for u, cs in users.items()}
our_root_pct = {u: (pct([ours[c]["vpl_root_m"] for c in cs]), pct([ours[c]["hpl_root_m"] for c in cs]))
                for u, cs in users.items()}
ref_pct = {v: {u: (pct([get(v, c, 1) for c in cs]), pct([get(v, c, 2) for c in cs])) for u, cs in users.items()
               if all(c in (ref[v] if v in ref else part[v]) for c in cs)}
           for v in list(ref) + list(part)}
gal = {}
if os.path.exists(args.galtable):
    for r in csv.DictReader(open(args.galtable)):
        gal[(float(r["lat_deg"]), float(r["lon_deg"]))] = (float(r["vpl_p995_m"]), float(r["hpl_p995_m"]))


def rel(a, b):
    return (b - a) / a


print()
print("| 99.5th-percentile PL per user, (reference - ours) / ours | users | mean | min | max | within 1 % |")
print("| --- | ---: | ---: | ---: | ---: | ---: |")
pairs = []
for v in list(ref) + list(part):
    if v == "v3":
        pairs.append((f"{names[v]}; ours: PL roots", v, our_root_pct))
    elif v == "refmodel":
        if gal:
            pairs.append((f"{names[v]}; ours: `airborne = \"galileo_e1e5a\"` (_galtable run)", v, gal))
    else:
        pairs.append((names[v], v, our_pct))
worst = {}
for label, v, base in pairs:
    for i, axis in ((0, "VPL"), (1, "HPL")):
        d = sorted(rel(base[u][i], ref_pct[v][u][i]) for u in users if u in ref_pct[v])
        within = sum(1 for x in d if abs(x) <= 0.01)
        print(f"| {axis}, {label} | {len(d)} | {100 * sum(d) / len(d):+.3f} % | {100 * d[0]:+.3f} % "
              f"| {100 * d[-1]:+.3f} % | {within} |")
        worst[(v, axis)] = max(abs(d[0]), abs(d[-1]))

def col(v, u, i):
    """A variant's column in the worst-user tables: (reference - ours) / ours,
    against our PL roots for v3."""
    if v not in ref_pct:
        return ""
    if u not in ref_pct[v]:
        return " not run |"
    b = our_root_pct if v == "v3" else our_pct
    return f" {100 * rel(b[u][i], ref_pct[v][u][i]):+.3f} % |"


print()
print("largest |difference| per variant: "
      + "; ".join(f"{v} {axis} {x:.2e}" for (v, axis), x in worst.items()))

if "published" in ref:
    print()
    print("Worst users, VPL 99.5th percentile (reference as published against ours), and the same user "
          "in the variants that remove a known cause:")
    print()
    head = "| user (lat, lon) | ours (m) | reference (m) | difference |"
    sep = "| --- | ---: | ---: | ---: |"
    if "all" in ref_pct:
        head += " every single event |"
        sep += " ---: |"
    if "v3" in ref_pct:
        head += " ADD v3.0 P_unmon, normal cdf, roots (against our root) |"
        sep += " ---: |"
    print(head)
    print(sep)
    order = sorted(users, key=lambda u: -abs(rel(our_pct[u][0], ref_pct["published"][u][0])))
    for u in order[:10]:
        o, r = our_pct[u][0], ref_pct["published"][u][0]
        line = f"| {u[0]:.0f}, {u[1]:.0f} | {o:.3f} | {r:.3f} | {100 * rel(o, r):+.3f} % |"
        line += col("all", u, 0) + col("v3", u, 0)
        print(line)
    print()
    print("Users whose HPL 99.5th percentile differs by more than 1 % (reference as published against ours):")
    print()
    head = "| user (lat, lon) | ours (m) | reference (m) | difference |"
    sep = "| --- | ---: | ---: | ---: |"
    if "all" in ref_pct:
        head += " every single event |"
        sep += " ---: |"
    if "v3" in ref_pct:
        head += " ADD v3.0 P_unmon, normal cdf, roots (against our root) |"
        sep += " ---: |"
    print(head)
    print(sep)
    hb = sorted((u for u in users if abs(rel(our_pct[u][1], ref_pct["published"][u][1])) > 0.01),
                key=lambda u: -abs(rel(our_pct[u][1], ref_pct["published"][u][1])))
    for u in hb:
        o, r = our_pct[u][1], ref_pct["published"][u][1]
        line = f"| {u[0]:.0f}, {u[1]:.0f} | {o:.3f} | {r:.3f} | {100 * rel(o, r):+.3f} % |"
        line += col("all", u, 1) + col("v3", u, 1)
        print(line)
    print()
    print("Users whose availability differs under the reference's rule (VPL < 35, HPL < 40 m), "
          "reference as published against our PLs:")
    a_ref = avails[(names["published"], "its rule: VPL < 35 and HPL < 40 m")]
    a_our = avails[rules[1][:2]]
    for u in sorted(users):
        if a_ref[u] != a_our[u]:
            cs = users[u]
            n = sum(1 for c in cs if (get("published", c, 1) < VAL and get("published", c, 2) < HAL)
                    != (ours[c]["vpl_m"] < VAL and ours[c]["hpl_m"] < HAL))
            print(f"- {u[0]:.0f}, {u[1]:.0f}: reference {100 * a_ref[u]:.2f} %, ours {100 * a_our[u]:.2f} % "
                  f"({n} epochs decided otherwise)")
    beyond = [u for u in users if abs(rel(our_pct[u][0], ref_pct["published"][u][0])) > 0.01]
    print()
    print(f"users beyond 1 % (VPL, as published): {len(beyond)}")
    for v in ("all", "v3"):
        if v in ref_pct and beyond:
            b = our_root_pct if v == "v3" else our_pct
            still = [u for u in beyond if u not in ref_pct[v] or abs(rel(b[u][0], ref_pct[v][u][0])) > 0.01]
            print(f"- of those, still beyond 1 % with {names[v]}: {len(still)}")
    mo = {}
    for c in ours:
        d = int(get("published", c, 0)) - int(ours[c]["modes"])
        mo[d] = mo.get(d, 0) + 1
    print("- monitored modes, reference - ours, per user-epoch: "
          + ", ".join(f"{k:+d}: {n}" for k, n in sorted(mo.items())))
