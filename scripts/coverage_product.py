#!/usr/bin/env python3
"""The product code's share of scripts/coverage.sh's measure, and the
justified exceptions (issue 37; docs/EVIDENCE.md "Structural coverage").

    python3 scripts/coverage_product.py LCOV.info SUMMARY.txt

LCOV.info is `llvm-cov export -format=lcov` over the on-device crates
(written by scripts/coverage.sh). For every source file it reads each
line's execution count (DA) and each branch outcome's (BRDA), then:

- leaves out the crates' own test code inside the source files: a
  `#[cfg(test)]` (or `#[cfg(all(test, ...))]`) item (`mod tests { ... }`, a test-only function) from its
  attribute to its closing brace. llvm-cov counts those lines as the
  product's, and a test's failure arm (`panic!` on a wrong answer) never
  runs when the tests pass;
- matches each uncovered line and branch outcome of the product code
  against docs/coverage_exceptions.txt (one justified exception per
  entry: the file (`*`: any), the text of the first line of the region,
  the reason;
  the region is that line's item up to its closing brace, or the line
  alone for a one-line item);
- appends to SUMMARY.txt: `product_lines`, `product_branches` (percent
  of the product code covered) and `justified_lines`,
  `justified_branches` (percent covered or listed as justified); writes
  the uncovered, unjustified lines to target/coverage/unjustified.txt.
"""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXCEPTIONS = os.path.join(ROOT, "docs", "coverage_exceptions.txt")

def parse_lcov(path):
    """{file: (lines {n: covered?}, branches {(line, block, branch): taken?})}
    from `llvm-cov export -format=lcov` (DA and BRDA records)."""
    files = {}
    cur = None
    with open(path) as fh:
        for raw in fh:
            tag, _, rest = raw.rstrip("\n").partition(":")
            if tag == "SF":
                cur = files.setdefault(rest, ({}, {}))
            elif tag == "DA" and cur is not None:
                n, c = rest.split(",")[:2]
                cur[0][int(n)] = cur[0].get(int(n), False) or int(c) > 0
            elif tag == "BRDA" and cur is not None:
                n, block, branch, taken = rest.split(",")
                key = (int(n), block, branch)
                cur[1][key] = cur[1].get(key, False) or (taken != "-" and int(taken) > 0)
    return files


def item_end(src, start):
    """The line (1-based) closing the item that begins at `start`: the
    first later line at the item's indentation that starts with `}`, or
    `start` itself when the item ends on its line (`;` or balanced)."""
    text = src[start - 1]
    indent = len(text) - len(text.lstrip())
    if text.rstrip().endswith(";") or text.count("{") == text.count("}") and "{" in text:
        return start
    for k in range(start, len(src)):
        t = src[k]
        if t.strip() and len(t) - len(t.lstrip()) == indent and t.lstrip().startswith("}"):
            return k + 1
    return len(src)


def test_ranges(src):
    """Line ranges of the `#[cfg(test)]` items of a source file."""
    out = []
    n = 0
    while n < len(src):
        t = src[n].strip()
        if t == "#[cfg(test)]" or (t.startswith("#[cfg(all(test,") and t.endswith("))]")):
            k = n + 1
            # Further attributes (a multi-line `#[allow(...)]` too) and comments.
            while k < len(src) and (src[k].strip().startswith("#[") or src[k].strip().startswith("//")):
                depth = src[k].count("[") - src[k].count("]")
                k += 1
                while depth > 0 and k < len(src):
                    depth += src[k].count("[") - src[k].count("]")
                    k += 1
            if k < len(src):
                out.append((n + 1, item_end(src, k + 1)))
                n = out[-1][1]
                continue
        n += 1
    return out


def load_exceptions():
    """[(path suffix, first-line text, reason)] from docs/coverage_exceptions.txt."""
    out = []
    if not os.path.exists(EXCEPTIONS):
        return out
    for raw in open(EXCEPTIONS):
        if not raw.strip() or raw.startswith("#"):
            continue
        parts = [p.strip() for p in raw.rstrip("\n").split(" | ")]
        if len(parts) != 3:
            sys.exit(f"coverage_exceptions.txt: not 'file | first line | reason': {raw.strip()}")
        out.append(tuple(parts))
    return out


def main():
    lcov, summary = sys.argv[1], sys.argv[2]
    files = parse_lcov(lcov)
    exceptions = load_exceptions()
    used = [0] * len(exceptions)
    tot = {"lines": [0, 0, 0], "branches": [0, 0, 0]}  # code, covered, justified
    unjustified = []
    crates = {}  # crate: [lines, covered, branches, covered, justified lines, justified branches]
    for path, (lines, branches) in sorted(files.items()):
        try:
            src = open(path).read().split("\n")
        except OSError:
            continue
        tests = test_ranges(src)

        def in_tests(n):
            return any(a <= n <= b for a, b in tests)

        regions = []
        for i, (suffix, first, _reason) in enumerate(exceptions):
            if suffix != "*" and not path.endswith("/" + suffix):
                continue
            hits = [k + 1 for k, t in enumerate(src) if t.strip() == first]
            if not hits and suffix != "*":
                sys.exit(f"coverage_exceptions.txt: no line '{first}' in {suffix}")
            for h in hits:
                end = item_end(src, h)
                if suffix == "*" and end - h > 2:
                    continue
                regions.append((h, end, i))

        def justified(n):
            for a, b, i in regions:
                if a <= n <= b:
                    used[i] += 1
                    return True
            return False

        rel = os.path.relpath(path, ROOT)
        crate = crates.setdefault(rel.split("/")[1] if rel.startswith("crates/") else rel, [0, 0, 0, 0, 0, 0])
        for n, covered in sorted(lines.items()):
            if in_tests(n):
                continue
            tot["lines"][0] += 1
            crate[0] += 1
            crate[1] += bool(covered)
            if covered:
                tot["lines"][1] += 1
            elif justified(n):
                tot["lines"][2] += 1
                crate[4] += 1
            else:
                unjustified.append(f"{rel}:{n}: {src[n - 1].strip()}")
        for (n, block, branch), hit in sorted(branches.items()):
            if in_tests(n):
                continue
            tot["branches"][0] += 1
            crate[2] += 1
            crate[3] += bool(hit)
            if hit:
                tot["branches"][1] += 1
            elif justified(n):
                tot["branches"][2] += 1
                crate[5] += 1
            else:
                unjustified.append(f"{rel}:{n}: branch {block}.{branch} never taken: {src[n - 1].strip()}")
    for i, (suffix, first, _r) in enumerate(exceptions):
        if used[i] == 0:
            print(f"coverage: exception covered now (remove it): {suffix} | {first}", file=sys.stderr)
    pct = {k: (100.0 * v[1] / v[0] if v[0] else 100.0) for k, v in tot.items()}
    just = {k: (100.0 * (v[1] + v[2]) / v[0] if v[0] else 100.0) for k, v in tot.items()}
    with open(summary, "a") as fh:
        fh.write(f"product_lines {pct['lines']:.2f}\nproduct_branches {pct['branches']:.2f}\n")
        fh.write(f"justified_lines {just['lines']:.2f}\njustified_branches {just['branches']:.2f}\n")
    out = os.path.join(os.path.dirname(summary), "unjustified.txt")
    with open(out, "w") as fh:
        fh.write("\n".join(unjustified) + "\n")
    for name, (n, c, b, bc, jl, jb) in sorted(crates.items()):
        print(
            f"  {name}: lines {100.0 * c / max(n, 1):.2f} % ({c} of {n}), "
            f"branches {100.0 * bc / max(b, 1):.2f} % ({bc} of {b}); "
            f"justified lines {100.0 * (c + jl) / max(n, 1):.2f} %, "
            f"branches {100.0 * (bc + jb) / max(b, 1):.2f} %"
        )
    L, B = tot["lines"], tot["branches"]
    print(
        f"product code (the test modules inside the sources left out): lines {pct['lines']:.2f} % "
        f"({L[1]} of {L[0]}), branches {pct['branches']:.2f} % ({B[1]} of {B[0]}); "
        f"with the {len(exceptions)} justified exceptions (docs/coverage_exceptions.txt): "
        f"lines {just['lines']:.2f} %, branches {just['branches']:.2f} %; "
        f"unjustified: {L[0] - L[1] - L[2]} lines, {B[0] - B[1] - B[2]} branch outcomes ({out})"
    )


if __name__ == "__main__":
    main()
