#!/usr/bin/env python3
"""MAAST for ARAIM 2 *as committed* (with its position optimisation,
`prm.opt = 1`) against `raim availability` with the adjusted position
estimator (`position = "adjusted"`, raim-core `araim::adjusted`) on the
MAAST scenario of issue 36, as Markdown tables for docs/AVAILABILITY.md
"The adjusted position estimator against MAAST for ARAIM 2".

    python3 scripts/maast2/compare_adjusted.py OUT [--write docs/AVAILABILITY.md]

(--write puts the tables between the maast2-adjusted markers of the file.)

OUT holds, beside what scripts/maast2/compare.py reads (MAAST 2's runs of
scripts/maast2/README.md, whose vpl_m, hpl_m, emt_m, sig_acc_m columns
are its outputs with the optimisation and the *_noopt_m ones without):
  ours_adj_fd/ours.csv           dump_sky --no-sky on docs/runs/availability_maast_g24e24_adjusted.toml
  ours_fd/ours.csv               the same on ..._ed259a.toml (plain estimator)
  ours_adj_sat1h/*.users.csv     raim availability on ..._adjusted_sat1h.toml

Availability, percentiles and coverage are defined as in compare.py.
"""
import csv
import glob
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare as c  # noqa: E402


def pct_hpl(data, users, times, k):
    return {u: c.pct([data[u][t][k] for t in times]) for u in users}


def rel_stats(pairs):
    r = sorted(c.rel(a, b) for a, b in pairs if math.isfinite(a) and math.isfinite(b))
    within = sum(1 for x in r if abs(x) <= 1.0)
    return (f"{statistics.median(r):+.3f} % | {r[0]:+.3f} .. {r[-1]:+.3f} % "
            f"| {100 * within / len(r):.2f} % | {len(r):,}")


def main():
    d = sys.argv[1]
    m, _, _ = c.read_maast(os.path.join(d, "matched_fd"))
    o = c.read_ours(os.path.join(d, "ours_adj_fd", "ours.csv"))
    p = c.read_ours(os.path.join(d, "ours_fd", "ours.csv"))
    users = sorted(set(m) & set(o))
    times = sorted(next(iter(m.values())).keys())
    assert all(len(m[u]) == len(times) for u in users), "MAAST run incomplete"
    assert all(t in o[users[0]] and t in p[users[0]] for t in times)
    opt = lambda v: (v[0], v[1], v[2], v[3], c.avail(v[:4]))  # noqa: E731
    noopt = lambda v: (v[4], v[5], v[6], v[7], c.avail(v[4:8]))  # noqa: E731
    ours = lambda v: v  # noqa: E731

    o_av, o_vp = c.per_user(o, users, times, ours)
    o_hp = pct_hpl(o, users, times, 1)
    print(f"Detection only, whole day: {len(users)} users x {len(times)} epochs "
          f"({len(users) * len(times):,} user-epochs):\n")
    print("| side | coverage at 99.5 % | at 99 % | area-weighted mean availability "
          "| user-epochs unavailable | available on this side only / on ours only "
          "| users on the other side of 99.5 % from ours |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows = [
        ("ours, `position = \"adjusted\"`", o, ours),
        ("MAAST for ARAIM 2 as committed (position optimisation)", m, opt),
        ("ours, plain estimator", p, ours),
        ("MAAST for ARAIM 2 before position optimisation", m, noopt),
    ]
    for name, src, pick in rows:
        av, _ = c.per_user(src, users, times, pick)
        n_unav = sum(1 for u in users for t in times if not pick(src[u][t])[4])
        here = sum(1 for u in users for t in times if pick(src[u][t])[4] and not o[u][t][4])
        there = sum(1 for u in users for t in times if o[u][t][4] and not pick(src[u][t])[4])
        flip = sum(1 for u in users if (av[u] >= 0.995) != (o_av[u] >= 0.995))
        print(f"| {name} | {c.fmt_pct(c.coverage(users, av, 0.995))} "
              f"| {c.fmt_pct(c.coverage(users, av, 0.99))} | {c.mean_av(users, av):.3f} % "
              f"| {n_unav} | {here} / {there} | {flip} |")

    adj_o = {(u, t) for u in users for t in times if o[u][t][:4] != p[u][t][:4]}
    adj_m = {(u, t) for u in users for t in times if m[u][t][:4] != m[u][t][4:8]}
    print(f"\nUser-epochs whose outputs the adjusted estimator gives: ours {len(adj_o)}, "
          f"MAAST 2 {len(adj_m)}, both {len(adj_o & adj_m)}.")

    m_av, m_vp = c.per_user(m, users, times, opt)
    m_hp = pct_hpl(m, users, times, 1)
    rv = [c.rel(m_vp[u], o_vp[u]) for u in users]
    rh = [c.rel(m_hp[u], o_hp[u]) for u in users]
    print(f"\nPer-user 99.5th-percentile PLs, MAAST 2 as committed (fast mode) against ours: "
          f"VPL mean {statistics.fmean(rv):+.2f} %, range {min(rv):+.2f} .. {max(rv):+.2f} %, "
          f"{sum(1 for x in rv if abs(x) > 1.0)} of {len(users)} users beyond 1 %; "
          f"HPL mean {statistics.fmean(rh):+.2f} %, range {min(rh):+.2f} .. {max(rh):+.2f} %, "
          f"{sum(1 for x in rh if abs(x) > 1.0)} beyond 1 %.")

    both = sorted(adj_o & adj_m)
    print("\nAt the user-epochs both sides adjust, MAAST 2 / ours - 1:\n")
    print("| MAAST 2 | output | median | range | within 1 % | user-epochs |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for k, name in ((0, "VPL"), (1, "HPL"), (2, "EMT"), (3, "sigma_v,acc")):
        print(f"| fast mode (as committed), whole day | {name} | "
              + rel_stats([(m[u][t][k], o[u][t][k]) for u, t in both]) + " |")
    ep, _, _ = c.read_maast(os.path.join(d, "matched_fd_nofast_1h"))
    if ep:
        st = sorted(next(iter(ep.values())).keys())
        adj_e = sorted((u, t) for u in users for t in st
                       if ep[u][t][:4] != ep[u][t][4:8] and (u, t) in adj_o)
        for k, name in ((0, "VPL"), (1, "HPL"), (2, "EMT"), (3, "sigma_v,acc")):
            print(f"| `prm.fast = 0`, every 12th epoch | {name} | "
                  + rel_stats([(ep[u][t][k], o[u][t][k]) for u, t in adj_e]) + " |")
        e_av, e_vp = c.per_user(ep, users, st, opt)
        e_hp = pct_hpl(ep, users, st, 1)
        s_av, s_vp = c.per_user(o, users, st, ours)
        s_hp = pct_hpl(o, users, st, 1)
        rv = [c.rel(e_vp[u], s_vp[u]) for u in users]
        rh = [c.rel(e_hp[u], s_hp[u]) for u in users]
        dis = sum(1 for u in users for t in st if c.avail(ep[u][t][:4]) != o[u][t][4])
        print(f"\nEvery 12th epoch ({len(st)} x {len(users)} user-epochs), MAAST 2 with "
              f"`prm.fast = 0` and its optimisation against ours adjusted: availability differs at "
              f"{dis} user-epochs; per-user 99.5th-percentile VPL mean {statistics.fmean(rv):+.2f} %, "
              f"range {min(rv):+.2f} .. {max(rv):+.2f} %, {sum(1 for x in rv if abs(x) > 1.0)} of "
              f"{len(users)} users beyond 1 %; HPL mean {statistics.fmean(rh):+.2f} %, range "
              f"{min(rh):+.2f} .. {max(rh):+.2f} %, {sum(1 for x in rh if abs(x) > 1.0)} beyond 1 %.")

    fde, _, fde_rows = c.read_maast(os.path.join(d, "matched_fde_1h"))
    ours_sat = glob.glob(os.path.join(d, "ours_adj_sat1h", "*.users.csv"))
    if fde and ours_sat:
        ft = sorted(next(iter(fde.values())).keys())
        osat = {}
        with open(ours_sat[0]) as fh:
            for r in csv.DictReader(fh):
                osat[(int(float(r["lat_deg"])), int(float(r["lon_deg"])))] = (
                    int(r["available"]), int(r["epochs"]))
        fu = sorted(set(fde) & set(osat))
        assert all(osat[u][1] == len(ft) for u in fu)
        print(f"\nWith exclusion, every 12th epoch ({len(ft)} epochs x {len(fu)} users = "
              f"{len(ft) * len(fu):,} user-epochs):\n")
        print("| side | coverage at 99.5 % | available user-epochs | users with the same count as ours "
              "| user-epochs more than ours / fewer |")
        print("| --- | ---: | ---: | ---: | ---: |")
        o_av2 = {u: osat[u][0] / osat[u][1] for u in fu}
        print(f"| ours, `exclusion = \"satellites\"`, `position = \"adjusted\"` "
              f"| {c.fmt_pct(c.coverage(fu, o_av2, 0.995))} | {sum(osat[u][0] for u in fu)} | - | - |")
        for label, sl in (("MAAST 2 with exclusion, as committed", slice(0, 4)),
                          ("MAAST 2 with exclusion, before position optimisation", slice(4, 8))):
            cnt = {u: sum(1 for t in ft if c.avail(fde[u][t][sl])) for u in fu}
            av2 = {u: cnt[u] / len(ft) for u in fu}
            same = sum(1 for u in fu if cnt[u] == osat[u][0])
            more = sum(max(0, cnt[u] - osat[u][0]) for u in fu)
            fewer = sum(max(0, osat[u][0] - cnt[u]) for u in fu)
            print(f"| {label} | {c.fmt_pct(c.coverage(fu, av2, 0.995))} | {sum(cnt.values())} "
                  f"| {same} of {len(fu)} | {more} / {fewer} |")


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[2] == "--write":
        import contextlib
        import io
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            main()
        s = open(sys.argv[3]).read()
        begin = "<!-- BEGIN generated: maast2-adjusted -->"
        end = "<!-- END generated: maast2-adjusted -->"
        i, j = s.index(begin) + len(begin), s.index(end)
        open(sys.argv[3], "w").write(s[:i] + "\n" + buf.getvalue().strip() + "\n" + s[j:])
    else:
        main()
