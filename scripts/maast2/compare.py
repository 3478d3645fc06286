#!/usr/bin/env python3
"""MAAST for ARAIM 2 (run under Octave by scripts/maast2/run.sh) against
`raim availability` on the MAAST scenario of issue 36
(docs/runs/availability_maast_g24e24_ed259a.toml), as Markdown tables for
docs/AVAILABILITY.md "Against MAAST for ARAIM 2".

    python3 scripts/maast2/compare.py OUT [--write docs/AVAILABILITY.md]

(--write puts the tables between the maast2-compare markers of the file.)

OUT holds (scripts/maast2/README.md):
  matched_fd.shard*.csv             MAAST 2, detection only, 288 epochs
  matched_fd_nofast.shard*.csv      the same with prm.fast = 0 (optional), or
  matched_fd_nofast_1h.shard*.csv   that on every 12th epoch
  shipped_fd_1h.shard*.csv          MAAST 2's own allocations, every 12th epoch (optional)
  matched_fde_1h.shard*.csv         MAAST 2 with exclusion, every 12th epoch
  ours_fd/ours.csv                  dump_sky --no-sky on the run file above
  ours_sat1h/*.users.csv            raim availability, ..._ed259a_sat1h.toml

Both sides count a user-epoch available when VPL <= 35 m, HPL <= 40 m,
EMT <= 15 m and sigma_v,acc <= 1.87 m (MAAST's coverage.m; ours: the
engine's decision, which adds its structural refusals), the 99.5th
percentile is sorted[ceil(0.995 n) - 1] on both (MAAST's
plot_no_gui_araim.m, ours SPEC 14), and coverage weighs users by
cos(latitude) (coverage.m). MAAST's grid has no 90 N row (its
init_usrdata stops at 90 - step); the comparison is on the 648 users both
have (the 90 N row weighs cos 90 deg ~ 6e-17 in our coverage).
"""
import csv
import glob
import math
import os
import statistics
import sys

T0_S = 345600.0
STEP_S = 300.0
VAL_M, HAL_M, EMT_M, SACC_M = 35.0, 40.0, 15.0, 1.87


def fnum(s):
    v = float(s)  # 'Inf', 'NaN', 'inf' parse
    return math.inf if math.isnan(v) else v


def read_maast(prefix):
    """{(lat, lon): {t: (vpl, hpl, emt, sacc, vpl0, hpl0, emt0, sacc0)}}, cpu_s, rows."""
    files = sorted(glob.glob(prefix + ".shard*.csv"))
    if not files:
        return None, 0.0, 0
    out, cpu, rows = {}, 0.0, 0
    for f in files:
        with open(f) as fh:
            head = fh.readline()
            cpu += float(head.split("cpu_s=")[1].split()[0])
            for r in csv.DictReader(fh):
                key = (int(float(r["lat_deg"])), int(float(r["lon_deg"])))
                v = tuple(fnum(r[c]) for c in (
                    "vpl_m", "hpl_m", "emt_m", "sig_acc_m",
                    "vpl_noopt_m", "hpl_noopt_m", "emt_noopt_m", "sig_acc_noopt_m"))
                out.setdefault(key, {})[float(r["t_s"])] = v
                rows += 1
    return out, cpu, rows


def read_ours(path):
    """{(lat, lon): {t: (vpl, hpl, emt, sacc, available)}}."""
    out = {}
    with open(path) as fh:
        for r in csv.DictReader(fh):
            key = (int(float(r["lat_deg"])), int(float(r["lon_deg"])))
            t = T0_S + STEP_S * int(r["epoch"])
            out.setdefault(key, {})[t] = (
                fnum(r["vpl_m"]), fnum(r["hpl_m"]), fnum(r["emt_m"]),
                fnum(r["sigma_v_acc_m"]), r["available"] == "1")
    return out


def avail(v):
    vpl, hpl, emt, sacc = v[:4]
    return vpl <= VAL_M and hpl <= HAL_M and emt <= EMT_M and sacc <= SACC_M


def pct(vals, level=0.995):
    s = sorted(vals)
    return s[math.ceil(level * len(s)) - 1]


def coverage(users, av, level):
    w = {u: math.cos(math.radians(u[0])) for u in users}
    return 100.0 * sum(w[u] for u in users if av[u] >= level) / sum(w.values())


def mean_av(users, av):
    w = {u: math.cos(math.radians(u[0])) for u in users}
    return 100.0 * sum(w[u] * av[u] for u in users) / sum(w.values())


def rel(a, b):
    if math.isinf(a) and math.isinf(b):
        return 0.0
    return 100.0 * (a / b - 1.0)


def per_user(data, users, times, pick):
    """availability and 99.5th-percentile VPL per user from `pick(v)` -> (vpl, hpl, emt, sacc, ok)."""
    av, vp = {}, {}
    for u in users:
        vals = [pick(data[u][t]) for t in times]
        av[u] = sum(1 for v in vals if v[4]) / len(vals)
        vp[u] = pct([v[0] for v in vals])
    return av, vp


def fmt_pct(x):
    return f"{x:.2f} %"


def main():
    d = sys.argv[1]
    m, m_cpu, m_rows = read_maast(os.path.join(d, "matched_fd"))
    o = read_ours(os.path.join(d, "ours_fd", "ours.csv"))
    users = sorted(set(m) & set(o))
    times = sorted(next(iter(m.values())).keys())
    assert all(len(m[u]) == len(times) for u in users), "MAAST run incomplete"
    assert all(t in o[users[0]] for t in times)

    nf, nf_cpu, nf_rows = read_maast(os.path.join(d, "matched_fd_nofast"))
    if nf:
        assert all(len(nf[u]) == len(times) for u in users), "fast = 0 run incomplete"
    opt = lambda v: (v[0], v[1], v[2], v[3], avail(v[:4]))  # noqa: E731
    noopt = lambda v: (v[4], v[5], v[6], v[7], avail(v[4:8]))  # noqa: E731
    sides = [
        ("MAAST for ARAIM 2 as committed (fast mode, position optimisation)", m, opt),
        ("MAAST for ARAIM 2, fast mode, before position optimisation", m, noopt),
    ]
    if nf:
        sides += [
            ("MAAST for ARAIM 2, `prm.fast = 0`, position optimisation", nf, opt),
            ("MAAST for ARAIM 2, `prm.fast = 0`, before position optimisation", nf, noopt),
        ]
    ours_pick = lambda v: v  # noqa: E731
    o_av, o_vp = per_user(o, users, times, ours_pick)

    print(f"Detection only, {len(users)} users x {len(times)} epochs "
          f"({len(users) * len(times):,} user-epochs):\n")
    print("| side | coverage at 99.5 % | at 99 % | area-weighted mean availability "
          "| user-epochs unavailable | users on the other side of 99.5 % from ours "
          "| per-user VPL (99.5th pct) against ours: mean, range | users beyond 1 % |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | --- | ---: |")
    n_unav = sum(1 for u in users for t in times if not o[u][t][4])
    print(f"| ours (`raim availability`, ADD v3.0, bracket PLs) | {fmt_pct(coverage(users, o_av, 0.995))} "
          f"| {fmt_pct(coverage(users, o_av, 0.99))} | {mean_av(users, o_av):.3f} % | {n_unav} | - | - | - |")
    results = {}
    for name, src, pick in sides:
        av, vp = per_user(src, users, times, pick)
        results[name] = (av, vp)
        n_unav = sum(1 for u in users for t in times if not pick(src[u][t])[4])
        flip = sum(1 for u in users if (av[u] >= 0.995) != (o_av[u] >= 0.995))
        r = [rel(vp[u], o_vp[u]) for u in users]
        beyond = sum(1 for x in r if abs(x) > 1.0)
        print(f"| {name} | {fmt_pct(coverage(users, av, 0.995))} | {fmt_pct(coverage(users, av, 0.99))} "
              f"| {mean_av(users, av):.3f} % | {n_unav} | {flip} "
              f"| {statistics.fmean(r):+.2f} %, {min(r):+.2f} .. {max(r):+.2f} % | {beyond} |")

    av, vp = results[sides[0][0]]
    flips = [u for u in users if (av[u] >= 0.995) != (o_av[u] >= 0.995)]
    by_lat = {}
    for u in flips:
        by_lat[abs(u[0])] = by_lat.get(abs(u[0]), 0) + 1
    if flips:
        print(f"\nUsers on the other side of 99.5 % (MAAST 2 as committed), by |latitude|: "
              + ", ".join(f"{k} deg: {v}" for k, v in sorted(by_lat.items()))
              + f"; our VPL percentile at them {min(o_vp[u] for u in flips):.1f}"
              f"-{max(o_vp[u] for u in flips):.1f} m.")
    sa = [(abs(m[u][t][7] / o[u][t][3] - 1.0), u, t) for u in users for t in times
          if math.isfinite(m[u][t][7]) and math.isfinite(o[u][t][3])]
    off = sorted((x for x in sa if x[0] > 2e-6), reverse=True)
    print(f"\nsigma_v,acc (before optimisation) against ours: within 2e-6 relative at "
          f"{len(sa) - len(off):,} of {len(sa):,} user-epochs; the others: "
          + ("; ".join(f"{u[0]}, {u[1]} at {t:.0f} s: {100 * r:.2f} %" for r, u, t in off) or "none") + ".")
    print("\nThe users whose 99.5th-percentile VPL differs most (MAAST 2 as committed against ours):\n")
    print("| user (lat, lon) | VPL ours (m) | VPL MAAST 2 (m) | difference | availability ours | availability MAAST 2 |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    worst = sorted(users, key=lambda u: -abs(rel(vp[u], o_vp[u])))[:6]
    for u in worst:
        print(f"| {u[0]}, {u[1]} | {o_vp[u]:.2f} | {vp[u]:.2f} | {rel(vp[u], o_vp[u]):+.2f} % "
              f"| {100 * o_av[u]:.2f} % | {100 * av[u]:.2f} % |")
    low = sorted(users, key=lambda u: (o_av[u], u))[:6]
    print("\nThe least available users:\n")
    av0, vp0 = results[sides[1][0]]
    print("| user (lat, lon) | availability ours | MAAST 2 as committed | MAAST 2 before optimisation "
          "| VPL ours (m) | VPL MAAST 2 as committed (m) | before optimisation (m) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for u in low:
        print(f"| {u[0]}, {u[1]} | {100 * o_av[u]:.2f} % | {100 * av[u]:.2f} % | {100 * av0[u]:.2f} % "
              f"| {o_vp[u]:.2f} | {vp[u]:.2f} | {vp0[u]:.2f} |")

    # Epoch by epoch, with MAAST's fast mode on and off.
    ep, ep_cpu, ep_rows = (nf, nf_cpu, nf_rows) if nf else read_maast(
        os.path.join(d, "matched_fd_nofast_1h"))
    if ep:
        sub_t = sorted(next(iter(ep.values())).keys())
        print(f"\nEpoch by epoch ({len(sub_t)} epochs x {len(users)} users = "
              f"{len(sub_t) * len(users):,} user-epochs), outputs before position optimisation, "
              "relative to ours (MAAST 2 / ours - 1; finite on both sides):\n")
        print("| MAAST 2 | output | median | 1st pct | 99th pct | max abs | within 1 % | user-epochs |")
        print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        for label, src in (("fast mode (as committed)", m), ("`prm.fast = 0` (every mode exact)", ep)):
            for k, name, ok in ((4, "VPL", 0), (5, "HPL", 1), (6, "EMT", 2), (7, "sigma_v,acc", 3)):
                r = [rel(src[u][t][k], o[u][t][ok]) for u in users for t in sub_t
                     if math.isfinite(src[u][t][k]) and math.isfinite(o[u][t][ok])]
                rs = sorted(r)
                within = sum(1 for x in r if abs(x) <= 1.0)
                print(f"| {label} | {name} | {statistics.median(r):+.3f} % | {rs[len(rs) // 100]:+.3f} % "
                      f"| {rs[(99 * len(rs)) // 100]:+.3f} % | {max(abs(x) for x in r):.3f} % "
                      f"| {100 * within / len(r):.2f} % | {len(r):,} |")
        hl = {}
        for u in users:
            for t in sub_t:
                a, b = ep[u][t][5], o[u][t][1]
                if math.isfinite(a) and math.isfinite(b):
                    n, k = hl.get(abs(u[0]), (0, 0))
                    hl[abs(u[0])] = (n + 1, k + (abs(rel(a, b)) > 1.0))
        print("\nHPL more than 1 % from ours (`prm.fast = 0`), share of user-epochs by |latitude|: "
              + ", ".join(f"{k} deg: {100 * v[1] / v[0]:.0f} %" for k, v in sorted(hl.items())) + ".")
        e_av, e_vp = per_user(ep, users, sub_t, lambda v: (v[4], v[5], v[6], v[7], avail(v[4:8])))
        s_av, s_vp = per_user(o, users, sub_t, ours_pick)
        r = [rel(e_vp[u], s_vp[u]) for u in users]
        print(f"\nPer-user 99.5th-percentile VPL over these epochs, `prm.fast = 0` before optimisation "
              f"against ours: mean {statistics.fmean(r):+.2f} %, range {min(r):+.2f} .. {max(r):+.2f} %, "
              f"{sum(1 for x in r if abs(x) > 1.0)} of {len(users)} users beyond 1 %.")
        for label, src in (("fast mode", m), ("`prm.fast = 0`", ep)):
            disagree = sum(1 for u in users for t in sub_t if avail(src[u][t][4:8]) != o[u][t][4])
            print(f"\nWith {label}, MAAST 2's availability before position optimisation differs "
                  f"from ours at {disagree} of {len(users) * len(sub_t):,} user-epochs.")

    sh, sh_cpu, _ = read_maast(os.path.join(d, "shipped_fd_1h"))
    if sh:
        st = sorted(next(iter(sh.values())).keys())
        print(f"\nMAAST 2's own V-ARAIM allocations (`MAAST2_CONFIG=shipped`: ADD v4.2 with 25 "
              f"effective samples, exposure 1/24 h, P_md cap, P_THRES 6e-8, P_FA,H 9e-7), fast mode, "
              f"every 12th epoch ({len(st)} epochs x {len(users)} users), against the matched run "
              "on the same epochs:\n")
        print("| MAAST 2 | user-epochs available (as committed) | before position optimisation "
              "| VPL before optimisation against matched: median, range |")
        print("| --- | ---: | ---: | --- |")
        for label, src in (("matched allocations", m), ("its own allocations", sh)):
            a1 = sum(1 for u in users for t in st if avail(src[u][t][:4]))
            a0 = sum(1 for u in users for t in st if avail(src[u][t][4:8]))
            r = [rel(src[u][t][4], m[u][t][4]) for u in users for t in st
                 if math.isfinite(src[u][t][4]) and math.isfinite(m[u][t][4])]
            print(f"| {label} | {a1} | {a0} | {statistics.median(r):+.2f} %, {min(r):+.2f} .. {max(r):+.2f} % |")

    fde, fde_cpu, fde_rows = read_maast(os.path.join(d, "matched_fde_1h"))
    every = "every 12th epoch"
    ours_sat = glob.glob(os.path.join(d, "ours_sat1h", "*.users.csv"))
    if fde and ours_sat:
        ft = sorted(next(iter(fde.values())).keys())
        osat = {}
        with open(ours_sat[0]) as fh:
            for r in csv.DictReader(fh):
                osat[(int(float(r["lat_deg"])), int(float(r["lon_deg"])))] = (
                    int(r["available"]), int(r["epochs"]))
        fu = sorted(set(fde) & set(osat))
        assert all(osat[u][1] == len(ft) for u in fu)
        print(f"\nWith exclusion, {every} ({len(ft)} epochs x {len(fu)} users = "
              f"{len(ft) * len(fu):,} user-epochs; MAAST 2 {fde_rows:,} rows read):\n")
        print("| side | coverage at 99.5 % (available at every epoch) | available user-epochs "
              "| users with the same count as ours |")
        print("| --- | ---: | ---: | ---: |")
        o_av2 = {u: osat[u][0] / osat[u][1] for u in fu}
        print(f"| ours, `exclusion = \"satellites\"` | {fmt_pct(coverage(fu, o_av2, 0.995))} "
              f"| {sum(osat[u][0] for u in fu)} | - |")
        for label, sl in (("MAAST 2 with exclusion, as committed", slice(0, 4)),
                          ("MAAST 2 with exclusion, before position optimisation", slice(4, 8))):
            cnt = {u: sum(1 for t in ft if avail(fde[u][t][sl])) for u in fu}
            av2 = {u: cnt[u] / len(ft) for u in fu}
            same = sum(1 for u in fu if cnt[u] == osat[u][0])
            print(f"| {label} | {fmt_pct(coverage(fu, av2, 0.995))} | {sum(cnt.values())} | {same} of {len(fu)} |")

    print("\nMAAST 2's CPU seconds (Octave's `cputime` around `svmrun_araim`, summed over the shards):\n")
    print("| MAAST 2 run | user-epochs | CPU s | user-epochs / CPU s |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| detection only, fast mode (as committed) | {m_rows:,} | {m_cpu:.1f} | {m_rows / m_cpu:.0f} |")
    if ep:
        print(f"| detection only, `prm.fast = 0`{'' if nf else ', every 12th epoch'} | {ep_rows:,} "
              f"| {ep_cpu:.1f} | {ep_rows / ep_cpu:.0f} |")
    if fde:
        print(f"| with exclusion, fast mode, {every} | {fde_rows:,} | {fde_cpu:.1f} | {fde_rows / fde_cpu:.1f} |")


def write_doc(doc, text):
    """Replace the block between the maast2-compare markers of `doc` with `text`."""
    begin, end = "<!-- BEGIN generated: maast2-compare -->", "<!-- END generated: maast2-compare -->"
    s = open(doc).read()
    i, j = s.index(begin) + len(begin), s.index(end)
    open(doc, "w").write(s[:i] + "\n" + text.strip() + "\n" + s[j:])


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[2] == "--write":
        import contextlib
        import io
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            main()
        write_doc(sys.argv[3], buf.getvalue())
    else:
        main()
