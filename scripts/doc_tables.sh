#!/usr/bin/env bash
# The generated tables of docs/ESQ.md, docs/MULTIFAULT.md and docs/BUDGET.md.
# Each table sits between two marker comments
#   <!-- BEGIN generated: NAME -->  ...  <!-- END generated: NAME -->
# and is rewritten from the output of the commands below; nothing between
# markers is typed by hand.
#
#   bash scripts/doc_tables.sh           # short mode: rewrite the short tables (about 1-2 min of CPU once built)
#   bash scripts/doc_tables.sh --check   # short mode, but compare with the committed docs; exit 1 on a difference (CI)
#   bash scripts/doc_tables.sh --long    # also the long Monte Carlo tables (about 15 min of CPU)
#
# Short (deterministic; replays of the shared real data and one unit test):
#   esq-nstar, esq-cost, pca-clean, pca-faults, esq-onsets (docs/ESQ.md), multifault-amplification (docs/MULTIFAULT.md).
# Long (seeded Monte Carlo; rerun by hand, not in CI):
#   multifault-mc (docs/MULTIFAULT.md), budget-mc (docs/BUDGET.md).
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=write
LONG=0
for a in "$@"; do
  case $a in
    --check) MODE=check ;;
    --long) LONG=1 ;;
    *) echo "usage: $0 [--check] [--long]" >&2; exit 2 ;;
  esac
done

cargo build --release -q -p raim-tool
R=./target/release/raim
G="--ura-m 0.3 --iono-vertical-m 0.5 --noise-m 0.2"
O="--obs ../shared/data/07590920.05o --nav ../shared/data/07590920.05n --systems G --mask-deg 15 --esq-pconst 1e-8"
E="--obs ../shared/data/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz --nav ../shared/data/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"
P="--obs ../shared/data/GEOP092I.24o.gz --nav ../shared/data/CORD00ARG_R_20240920000_01D_MN.rnx.gz --systems GE"

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
# In check mode the tables are written into copies of the docs.
DOCS=docs
if [ $MODE = check ]; then
  mkdir -p "$TMP/docs"
  cp docs/ESQ.md docs/MULTIFAULT.md docs/BUDGET.md "$TMP/docs/"
  DOCS=$TMP/docs
fi

# put DOC NAME FILE: the lines of FILE replace what lies between the markers.
put() {
  local doc=$1 name=$2 file=$3
  grep -q "<!-- BEGIN generated: $name -->" "$doc" || { echo "$doc: no marker $name" >&2; exit 1; }
  awk -v b="<!-- BEGIN generated: $name -->" -v e="<!-- END generated: $name -->" -v f="$file" '
    index($0, b) == 1 { print; while ((getline l < f) > 0) print l; skip = 1; next }
    index($0, e) == 1 { skip = 0 }
    !skip { print }' "$doc" >"$doc.new"
  mv "$doc.new" "$doc"
}

# field LABEL TEXT: the word after LABEL in TEXT.
field() { sed -n "s/.*$1 \([^ ;,]*\).*/\1/p" <<<"$2" | head -1; }

# --- ESQ: N*, the evaluations saved, and the delay with onsets on a window opening.
esq() { "$R" replay "$@" $G --esq --quiet; }
f=$TMP/esq-nstar
{
  echo "| file | N\\* (min / median / max) | ARAIM evaluations: every epoch -> effective | saved |"
  echo "| --- | --- | --- | --- |"
  nstar() { # label, args...
    local label=$1; shift
    local out s1 s2
    # shellcheck disable=SC2086
    out=$(esq "$@")
    s1=$(grep "^ESQ summary" <<<"$out")
    s2=$(grep "^  solves" <<<"$out")
    echo "| $label | $(field min "$s1") / $(field median "$s1") / $(field max "$s1") | $(field "every epoch" "$s2") -> $(field "effective samples" "$s2") ($(sed -n 's/.*saved; \([0-9.]*\) per window.*/\1/p' <<<"$s2") per window) | $(sed -n 's/.*(\([0-9.]*\) % saved.*/\1/p' <<<"$s2") % |"
  }
  # shellcheck disable=SC2086
  nstar "ESBC (G+E+C), T 300 s" $E
  # shellcheck disable=SC2086
  nstar "ESBC, T 600 s" $E --esq-window-s 600
  # shellcheck disable=SC2086
  nstar "ESBC, T 120 s" $E --esq-window-s 120
  # shellcheck disable=SC2086
  nstar "0759 (GPS), T 300 s" $O
} >"$f"
put "$DOCS/ESQ.md" esq-nstar "$f"
f=$TMP/esq-cost
{
  echo "| run | first alarm, every epoch | first alarm, effective samples | faulted epochs alarmed / evaluated (missed by skipping) |"
  echo "| --- | --- | --- | --- |"
  cost() { # label, args...
    local label=$1; shift
    local l
    # shellcheck disable=SC2086
    l=$(grep "after onset" <<<"$(esq "$@")")
    echo "| $label | $(sed -n 's/.*first alarm every epoch \([^,]*\),.*/\1/p' <<<"$l") | $(sed -n 's/.*effective samples \([^;]*\);.*/\1/p' <<<"$l") | $(field "alarmed" "$l") / $(field "evaluated" "$l") ($(sed -n 's/.*missed by skipping \([0-9]*\)).*/\1/p' <<<"$l")) |"
  }
  # shellcheck disable=SC2086
  cost "ESBC step 10 m G15" $E --fault step:G15:10@01:00:00
  # shellcheck disable=SC2086
  cost "ESBC step 5 m G15" $E --fault step:G15:5@01:00:00
  # shellcheck disable=SC2086
  cost "ESBC ramp 0.01 m/s G15" $E --fault ramp:G15:0.01@01:00:00
  # shellcheck disable=SC2086
  cost "ESBC ramp 0.05 m/s G15" $E --fault ramp:G15:0.05@01:00:00
  # shellcheck disable=SC2086
  cost "0759 step 10 m G24" $O --fault step:G24:10@00:20:00
  # shellcheck disable=SC2086
  cost "0759 ramp 0.01 m/s G24" $O --fault ramp:G24:0.01@00:20:00
} >"$f"
put "$DOCS/ESQ.md" esq-cost "$f"

# --- PCA on the clean files: the nominal null, and the empirical null fitted on ESBC.
pca() { "$R" replay "$@" $G --pca --quiet; }
esbc=$(pca $E)
C=$(field "fitted Gaussian scale" "$esbc")
f=$TMP/pca-clean
{
  echo "| file | tested epochs | false alarms, nominal threshold | binomial 99 % bound at 3.9e-6 | largest ratio | 99th percentile of abs(u) | Gaussian scale fitted on the file | false alarms at c = $C x nominal (c fitted on ESBC) |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
  for spec in "ESBC|$E" "0759|$O" "GEOP|$P"; do
    name=${spec%%|*} args=${spec#*|}
    # shellcheck disable=SC2086
    nom=$(pca $args)
    # shellcheck disable=SC2086
    emp=$(pca $args --pca-null-scale "$C")
    line=$(grep "against the allocation" <<<"$nom")
    uline=$(grep "standardized separations" <<<"$nom")
    tested=$(sed -n 's/.* in \([0-9]*\) clean tested epochs.*/\1/p' <<<"$line")
    fa=$(sed -n 's/.*allocation: \([0-9]*\) in.*/\1/p' <<<"$line")
    bound=$(sed -n 's/.*99 % bound \([0-9]*\):.*/\1/p' <<<"$line")
    maxr=$(sed -n 's/.*max before onset \([0-9.]*\).*/\1/p' <<<"$nom")
    q99=$(field "99th percentile" "$uline")
    scale=$(field "fitted Gaussian scale" "$uline")
    fa_emp=$(sed -n 's/.*allocation: \([0-9]*\) in.*/\1/p' <<<"$(grep "against the allocation" <<<"$emp")")
    note=""
    [ "$name" = ESBC ] && note=" (in-sample)"
    echo "| $name | $tested | $fa | $bound | $maxr | $q99 | $scale | $fa_emp$note |"
  done
} >"$f"
put "$DOCS/ESQ.md" pca-clean "$f"

# --- PCA against constellation-wide faults on ESBC, at c x nominal.
f=$TMP/pca-faults
{
  echo "| fault (from 01:00:00) | PCA: first alarm | PCA: faulted epochs alarmed | PCA: alarms before the onset | PCA: largest ratio / c in the first 5 faulted epochs | ARAIM (any mode): first alarm | snapshot: first alarm |"
  echo "| --- | --- | --- | --- | --- | --- | --- |"
  row() { # label, fault args
    local label=$1; shift
    local out
    # shellcheck disable=SC2086
    out=$(pca $E --pca-null-scale "$C" "$@")
    m() { grep "^  $1 " <<<"$out"; }
    delay() { sed -n 's/.*delay \([^|]*\) |.*/\1/p' <<<"$(m "$1")" | sed 's/ *$//'; }
    alarmed() { sed -n 's/.*alarmed \([0-9/]*\).*/\1/p' <<<"$(m "$1")"; }
    before() { sed -n 's/.*false alarms *\([0-9]*\) .*/\1/p' <<<"$(m "$1")"; }
    local r5
    r5=$(sed -n 's/.*first 5 faulted epochs \([0-9.]*\).*/\1/p' <<<"$out")
    r5=$(awk -v r="$r5" -v c="$C" 'BEGIN { printf "%.2f", r / c }')
    echo "| $label | $(delay PCA) | $(alarmed PCA) | $(before PCA) | $r5 | $(delay "ARAIM (any mode)") | $(delay snapshot) |"
  }
  for sys in E C; do
    for b in 5 10 50; do row "$sys-wide bias $b m" --fault "step:$sys:$b@01:00:00"; done
    for r in 0.01 0.05; do row "$sys-wide ramp $r m/s" --fault "ramp:$sys:$r@01:00:00"; done
    for x in 10 200; do row "$sys ephemeris, radial $x m" --eph-fault "$sys:$x@01:00:00"; done
  done
  row "G15 step 10 m (one satellite)" --fault step:G15:10@01:00:00
} >"$f"
put "$DOCS/ESQ.md" pca-faults "$f"

# --- The ESQ resampler: onsets uniform over the window T = 300 s (and the epoch).
f=$TMP/esq-onsets
N_ONSETS=80
{
  echo "| fault | evaluated | detected (95 % interval) | delay median [95 % interval] | delay 95th percentile [95 % interval] |"
  echo "| --- | --- | --- | --- | --- |"
  sweep() { # label, file args, fault
    local label=$1 args=$2 fault=$3 out
    # shellcheck disable=SC2086
    out=$("$R" replay $args $G --esq --quiet --fault "$fault" --esq-onset-sweep $N_ONSETS --esq-onset-seed 1)
    for which in "every epoch" "effective samples"; do
      local l
      l=$(grep "^  $which " <<<"$out")
      local det med p95
      det=$(sed -n 's/.*detected \([0-9/]*\) = \([0-9.]*\) \(\[[^]]*\]\).*/\1 = \2 \3/p' <<<"$l")
      med=$(sed -n 's/.*delay median \([^|]*\) |.*/\1/p' <<<"$l" | sed 's/ *$//')
      p95=$(sed -n 's/.*p95 \(.*\)$/\1/p' <<<"$l")
      echo "| $label | $which | $det | $med | $p95 |"
    done
  }
  sweep "ESBC step 10 m G15" "$E" step:G15:10@01:00:00
  sweep "ESBC step 5 m G15" "$E" step:G15:5@01:00:00
  sweep "ESBC ramp 0.01 m/s G15" "$E" ramp:G15:0.01@01:00:00
  sweep "ESBC ramp 0.05 m/s G15" "$E" ramp:G15:0.05@01:00:00
  sweep "0759 step 10 m G24" "$O" step:G24:10@00:20:00
  sweep "0759 ramp 0.01 m/s G24" "$O" ramp:G24:0.01@00:20:00
} >"$f"
put "$DOCS/ESQ.md" esq-onsets "$f"

# --- Seed 002: the reconstruction's noise amplification sqrt(diag S[F,F]^-1).
f=$TMP/multifault-amplification
{
  echo "| group F (identifiable set) | sigma(e_i) / sigma, i in F |"
  echo "| --- | --- |"
  cargo test -q -p raim-core --release --lib seed_002_reconstruction_is_linear -- --nocapture 2>/dev/null \
    | sed -n 's/^group \({[0-9,]*}\): sigma(e_i) \/ sigma = \(.*\)$/| \1 | \2 |/p'
} >"$f"
[ "$(wc -l <"$f")" -eq 5 ] || { echo "multifault-amplification: expected 3 groups" >&2; cat "$f" >&2; exit 1; }
put "$DOCS/MULTIFAULT.md" multifault-amplification "$f"

if [ $LONG = 1 ]; then
  f=$TMP/multifault-mc
  cargo run -q --release -p raim-core --example multifault_mc -- 30000 11 1000 >"$f"
  put "$DOCS/MULTIFAULT.md" multifault-mc "$f"
  f=$TMP/budget-mc
  cargo run -q --release -p raim-core --example budget_mc -- 10000000 1e-5 0.5 0.3 0.2 1 2 >"$f"
  put "$DOCS/BUDGET.md" budget-mc "$f"
fi

if [ $MODE = check ]; then
  status=0
  for d in ESQ.md MULTIFAULT.md BUDGET.md; do
    if ! diff -u "docs/$d" "$DOCS/$d"; then
      echo "docs/$d: a generated table differs from what the code produces now (bash scripts/doc_tables.sh)" >&2
      status=1
    fi
  done
  exit $status
fi
echo "rewrote the generated tables of docs/ESQ.md docs/MULTIFAULT.md docs/BUDGET.md"
