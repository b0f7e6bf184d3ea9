#!/usr/bin/env bash
# Reproduces every experiment of Goswami et al. (arXiv 1410.3864) on real agent processes over loopback
# and in shapeform_sim from the same starting positions, then draws the figures paper_*.png and writes
# RESULTS.md (the hand-written text above and below its generated part is kept).
#
#   scripts/reproduce_paper.sh [--quick] [--build DIR] [--data DIR] [--domain D] [--direct] [--write-docs]
#
#   --quick       shortened runs: 200 iterations everywhere (about half the time)
#   --build DIR   build folder holding bin/ (default: build; configured and built, Release, if missing)
#   --data DIR    the run folder: recorded CSV files, figures/ and RESULTS.md
#                 (default: runs/<UTC time>-paper)
#   --domain D    first of 9 DDS domain ids the experiments cycle through (default 131: 131..139)
#   --direct      start the processes here instead of through scripts/launch_swarm.sh
#   --write-docs  also rewrite the committed docs/RESULTS.md and docs/figures/paper_*.png
#
# Three steps, each its own program: scripts/paper/run.py (the runs, one line of progress each: the four
# shapes, the repulsion study, tracking on both paths without and with feed-forward and around a fixed
# centre, then simulator-only studies of the published law's limits), scripts/plot_paper.py (figures)
# and scripts/paper/report.py (RESULTS.md, from the run folder alone; scripts/paper/analyse.py is the
# analysis). Exit status: 0 when every run completed, 1 otherwise, 2 for bad arguments.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3 # Debian's python3 with python3-matplotlib (scripts/install_deps.sh)
export PYTHONDONTWRITEBYTECODE=1 # no __pycache__ in scripts/

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; }
die() { echo "reproduce_paper: $*" >&2; exit 2; }
quick=() build="$root/build" data="" domain=131 backend=auto docs=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=(--quick); shift ;;
    --build) [ $# -ge 2 ] || die "--build: missing value"; build=$2; shift 2 ;;
    --data) [ $# -ge 2 ] || die "--data: missing value"; data=$2; shift 2 ;;
    --domain) [ $# -ge 2 ] || die "--domain: missing value"; domain=$2; shift 2 ;;
    --direct) backend=direct; shift ;;
    --write-docs) docs=(--write-docs); shift ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[[ $domain =~ ^[0-9]+$ ]] && [ "$domain" -le 224 ] || die "--domain: expected 0..224, got '$domain'"
case "$build" in /*) ;; *) build="$PWD/$build" ;; esac
[ -n "$data" ] || data="$root/runs/$(date -u +%Y%m%dT%H%M%SZ)-paper"
"$py" -c 'import matplotlib, numpy' 2>/dev/null || {
  echo "reproduce_paper: $py lacks matplotlib/numpy; run scripts/install_deps.sh (python3-matplotlib)" >&2
  exit 2
}
if [ ! -x "$build/bin/shapeform_agent" ] || [ ! -x "$build/bin/shapeform_supervisor" ] || [ ! -x "$build/bin/shapeform_sim" ]; then
  echo "reproduce_paper: building into $build" >&2
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build" -j"$(nproc)" >/dev/null
fi

start=$(date +%s)
status=0
"$py" "$root/scripts/paper/run.py" --build "$build" --data "$data" --domain "$domain" \
  --backend "$backend" "${quick[@]}" || status=1
"$py" "$root/scripts/plot_paper.py" --data "$data"
"$py" "$root/scripts/paper/report.py" --data "$data"
if [ ${#docs[@]} -gt 0 ]; then
  cp "$data"/figures/paper_*.png "$root/docs/figures/"
  "$py" "$root/scripts/paper/report.py" --data "$data" --write-docs
  echo "reproduce_paper: rewrote docs/RESULTS.md and docs/figures/paper_*.png" >&2
fi
echo "reproduce_paper: done in $(($(date +%s) - start)) s; run folder $data (RESULTS.md, figures/, data)"
exit $status
