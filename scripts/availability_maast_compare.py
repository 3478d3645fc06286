#!/usr/bin/env python3
"""Compares our engine's detection-only outputs (ours.csv, examples/dump_sky.rs)
with the ADD v4.2 reference implementation's on the same user-epochs (ref.csv,
scripts/octave/availability_maast_compare.m). Prints a Markdown summary
(docs/AVAILABILITY.md "Against the ADD v4.2 reference implementation").
Usage: availability_maast_compare.py WORK_DIR"""
import csv
import sys

work = sys.argv[1]
ours = {r["case"]: r for r in csv.DictReader(open(f"{work}/ours.csv"))}
ref = {r["case"]: r for r in csv.DictReader(open(f"{work}/ref.csv"))}
assert ours.keys() == ref.keys(), "the two files cover different user-epochs"
VAL, HAL = 35.0, 40.0


def stats(name, a_key, b_key, src_a, src_b):
    rel = []
    for c in ours:
        a, b = float(src_a[c][a_key]), float(src_b[c][b_key])
        rel.append((b - a) / a)
    rel.sort()
    n = len(rel)
    mean = sum(rel) / n
    worst = max(rel, key=abs)
    within = sum(1 for x in rel if abs(x) <= 0.01)
    print(f"| {name} | {n} | {100 * mean:+.3f} % | {100 * rel[0]:+.3f} % | {100 * rel[-1]:+.3f} % "
          f"| {100 * worst:+.3f} % | {within} |")


print(f"user-epochs: {len(ours)}")
print()
print("| quantity (reference - ours) / ours | user-epochs | mean | min | max | worst | within 1 % |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
stats("VPL, same C_int/C_acc", "vpl_m", "vpl_m", ours, ref)
stats("HPL, same C_int/C_acc", "hpl_m", "hpl_m", ours, ref)
stats("VPL, same C_int/C_acc, every single event monitored", "vpl_m", "vpl_all_m", ours, ref)
stats("HPL, same C_int/C_acc, every single event monitored", "hpl_m", "hpl_all_m", ours, ref)
stats("VPL root (both: exact root; every single event monitored)", "vpl_root_m", "vpl_root_m", ours, ref)
stats("HPL root (both: exact roots; every single event monitored)", "hpl_root_m", "hpl_root_m", ours, ref)
stats("VPL root, the reference's functions with ADD v3.0's P_unmon", "vpl_root_m", "vpl_v3_m", ours, ref)
stats("HPL root, the reference's functions with ADD v3.0's P_unmon", "hpl_root_m", "hpl_v3_m", ours, ref)
stats("VPL, reference error model", "vpl_m", "vpl_refmodel_m", ours, ref)
stats("VPL, reference error model against the same inputs, both in the reference", "vpl_m", "vpl_refmodel_m", ref, ref)
stats("HPL, reference error model", "hpl_m", "hpl_refmodel_m", ours, ref)
print()
modes = [(int(ours[c]["modes"]), int(ref[c]["modes"])) for c in ours]
diff = {}
for o, r in modes:
    diff[r - o] = diff.get(r - o, 0) + 1
print("monitored modes, reference - ours: " + ", ".join(f"{k:+d}: {v} user-epochs" for k, v in sorted(diff.items())))
diff = {}
for c in ours:
    d = int(ref[c]["modes_all"]) - int(ours[c]["modes"])
    diff[d] = diff.get(d, 0) + 1
print("monitored modes, reference with every single event - ours: "
      + ", ".join(f"{k:+d}: {v} user-epochs" for k, v in sorted(diff.items())))
agree = sum(
    1
    for c in ours
    if (float(ours[c]["vpl_m"]) <= VAL and float(ours[c]["hpl_m"]) <= HAL)
    == (float(ref[c]["vpl_m"]) <= VAL and float(ref[c]["hpl_m"]) <= HAL)
)
print(f"VPL <= 35 m and HPL <= 40 m decided alike (same inputs): {agree} of {len(ours)}")
gps = max(float(ref[c]["max_dcint_gps_m2"]) for c in ref)
pr = [float(ref[c]["p_unmon_ref"]) for c in ref]
p3 = [float(ref[c]["p_unmon_v3"]) for c in ref]
print(f"P_unmon, the reference's: {min(pr):.3g} to {max(pr):.3g}; ADD v3.0's: {min(p3):.3g} to {max(p3):.3g}")
print(f"largest |GPS airborne + tropo variance, reference - ours|: {gps:.3g} m^2")
