#!/usr/bin/env python3
"""Exact covering designs C(n, k, t) for seed 002's constraint groups (SPEC §8.3).

A group's identifiable set F has k = n - m satellites; every t-subset of the n
satellites must lie inside some F. The minimum number of groups is the covering
number C(n, k, t). This script finds it by integer linear programming (PuLP with
its bundled CBC): one binary variable per k-subset B, minimise sum x_B subject to
sum_{B contains T} x_B >= 1 for every t-subset T. CBC proves optimality.

Run (offline, once; the output is committed):
    python3 -m venv /tmp/mfvenv && /tmp/mfvenv/bin/pip install pulp
    /tmp/mfvenv/bin/python tools/covering/exact_covering.py \
        > crates/raim-core/src/multifault/covering_table.rs

The Rust side (`covering::tests`) re-checks every committed design: each one
covers every t-subset and has the stated size. Satellite i is bit i of a mask.
"""
import itertools
import sys
import time

import pulp

M_VALUES = (4, 5)
N_RANGE = range(6, 13)
T_MAX = 3
TIME_LIMIT_S = 150


def schoenheim(n, k, t):
    """The Schoenheim lower bound L(n, k, t) = ceil(n/k L(n-1, k-1, t-1))."""
    if t == 0:
        return 1
    inner = schoenheim(n - 1, k - 1, t - 1)
    return -(-n * inner // k)


def exact(n, k, t):
    blocks = list(itertools.combinations(range(n), k))
    prob = pulp.LpProblem("covering", pulp.LpMinimize)
    x = [pulp.LpVariable(f"x{i}", cat="Binary") for i in range(len(blocks))]
    prob += pulp.lpSum(x)
    # Symmetry: relabelling the satellites maps any design to one that
    # holds the block {0..k-1}. The Schoenheim bound is a valid cut.
    prob += x[0] == 1
    prob += pulp.lpSum(x) >= schoenheim(n, k, t)
    sets = [set(b) for b in blocks]
    for tt in itertools.combinations(range(n), t):
        prob += pulp.lpSum(x[i] for i, b in enumerate(sets) if set(tt) <= b) >= 1
    status = prob.solve(pulp.PULP_CBC_CMD(msg=False, timeLimit=TIME_LIMIT_S))
    # CBC stopped by its time limit reports status "Optimal" with an
    # integer-feasible solution; only sol_status 1 is a proof.
    optimal = pulp.LpStatus[status] == "Optimal" and prob.sol_status == pulp.LpSolutionOptimal
    chosen = [blocks[i] for i in range(len(blocks)) if x[i].value() > 0.5]
    return chosen, optimal


def mask(block):
    return sum(1 << i for i in block)


def main():
    out = []
    out.append("//! Exact covering designs C(n, n - m, t) for n = 6..12, m = 4 and 5,")
    out.append("//! t = 1..3 (t <= n - m - 1), found offline by integer linear programming")
    out.append("//! (`tools/covering/exact_covering.py`, PuLP + CBC; optimal where not marked,")
    out.append("//! the best found in the time limit where marked). Generated: do not edit; docs/MULTIFAULT.md has the")
    out.append("//! command. Each entry: (n, m, t, identifiable sets as bit masks).")
    out.append("")
    out.append("/// (n, m, t, the groups' identifiable sets; satellite i is bit i).")
    out.append("pub(crate) static EXACT: &[(u8, u8, u8, &[u64])] = &[")
    for m in M_VALUES:
        for n in N_RANGE:
            k = n - m
            for t in range(1, T_MAX + 1):
                if t > k - 1:
                    continue
                t0 = time.time()
                chosen, optimal = exact(n, k, t)
                dt = time.time() - t0
                lb = schoenheim(n, k, t)
                print(f"n={n} m={m} k={k} t={t}: {len(chosen)} groups, optimal={optimal}, "
                      f"Schoenheim bound {lb}, {dt:.1f}s", file=sys.stderr, flush=True)
                if not optimal:
                    print("  NOT PROVEN OPTIMAL", file=sys.stderr)
                masks = ", ".join(f"0x{mask(b):x}" for b in chosen)
                note = "" if optimal else f" // not proven optimal in {TIME_LIMIT_S} s (lower bound {lb})"
                out.append(f"    ({n}, {m}, {t}, &[{masks}]),{note}")
    out.append("];")
    print("\n".join(out))


if __name__ == "__main__":
    main()
