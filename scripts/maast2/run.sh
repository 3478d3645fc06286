#!/usr/bin/env bash
# MAAST for ARAIM 2 (stanford-gps-lab/maast_for_araim_2), run under GNU
# Octave on the MAAST scenario of issue 36, without its GUI, from a patched
# copy outside this repository (scripts/maast2/README.md says what each
# patch is and why it leaves the numbers alone). Not run by CI: needs
# Octave and the two Stanford repositories.
#
#   bash scripts/maast2/run.sh setup MAAST2_GIT MAAST_GIT WORK
#   bash scripts/maast2/run.sh run WORK CONFIG FDE T0 T1 STEP SHARDS OUT_PREFIX
#
# setup: extracts MAAST for ARAIM 2 at ab70e2a3 (2024-07-17) into WORK/maast2
#   and the SBAS MAAST it builds on at 091f8dea (2024-11-01, the last commit
#   before init_satdata.m was renamed to init_satdata_pub.m, which MAAST 2
#   calls by its old name) into WORK/maast, converts the two CR-only files
#   to LF and applies scripts/maast2/maast2.patch.
# run: CONFIG matched|shipped (run_maast2.m), FDE 0|1, epochs T0, T0+STEP,
#   ... < T1 (GPS seconds of the almanacs' week 703) in SHARDS niced Octave
#   processes, each over a contiguous block of epochs; writes
#   OUT_PREFIX.shardK.csv and the log OUT_PREFIX.log.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cmd=${1:?usage: run.sh setup|run ...}
shift
case "$cmd" in
setup)
  m2=${1:?MAAST2_GIT}; m1=${2:?MAAST_GIT}; work=${3:?WORK}
  mkdir -p "$work/maast2" "$work/maast"
  git --git-dir="$m2" archive ab70e2a3e9735deb859028fb4ad23f816cfa1998 | tar -x -C "$work/maast2"
  # git archive of the SBAS MAAST stops at objects missing from the mirror
  # (test data); copy the top-level files one by one instead.
  git --git-dir="$m1" ls-tree 091f8dea8b389c6b6e51782b02ade1f12a829d7b |
    while read -r _mode type obj name; do
      [ "$type" = blob ] || continue
      git --git-dir="$m1" cat-file blob "$obj" >"$work/maast/$name" 2>/dev/null ||
        { rm -f "$work/maast/$name"; echo "skipped (not in the mirror): $name"; }
    done
  cd "$work/maast2"
  for f in usr_vhpl_araim.m usrprocess_araim.m; do
    tr '\r' '\n' <"$f" >"$f.lf" && mv "$f.lf" "$f"
  done
  patch -p1 <"$here/maast2.patch"
  ;;
run)
  work=$(cd "${1:?WORK}" && pwd); config=${2:?CONFIG}; fde=${3:?FDE}
  t0=${4:?T0}; t1=${5:?T1}; step=${6:?STEP}; shards=${7:?SHARDS}; out=${8:?OUT_PREFIX}
  n=$(( (t1 - t0 + step - 1) / step ))
  pids=()
  for ((k = 0; k < shards; k++)); do
    a=$(( k * n / shards )); b=$(( (k + 1) * n / shards ))
    MAAST2_CONFIG=$config MAAST2_FDE=$fde MAAST2_T0=$(( t0 + a * step )) \
      MAAST2_T1=$(( t0 + b * step )) MAAST2_STEP=$step MAAST2_OUT="$out.shard$k.csv" \
      nice octave-cli --eval "cd('$work/maast2'); addpath('$work/maast', '-end'); addpath('$here/octave'); addpath('$here'); run_maast2" \
      2>&1 | grep --line-buffered -E '^(maast2 done|Time:|error)' | sed -u "s/^/shard $k: /" >>"$out.log" &
    pids+=($!)
  done
  for p in "${pids[@]}"; do wait "$p"; done
  grep -h '^maast2 done' "$out.log" >/dev/null || true
  ;;
*) echo "unknown command $cmd" >&2; exit 2 ;;
esac
