#!/usr/bin/env bash
# Reproduces every experiment of Goswami et al. (arXiv 1410.3864) on real agent processes over loopback
# and in shapeform_sim from the same starting positions, then draws docs/figures/paper_*.png and writes
# docs/RESULTS.md (the hand-written text above and below its generated part is kept).
#
#   scripts/reproduce_paper.sh [--quick] [--build DIR] [--data DIR] [--domain D] [--direct]
#
#   --quick       shortened runs: 200 iterations everywhere (about half the time)
#   --build DIR   build folder holding bin/ (default: build; configured and built, Release, if missing)
#   --data DIR    where the recorded CSV files go (default: BUILD/paper)
#   --domain D    first of 9 DDS domain ids the experiments cycle through (default 131: 131..139)
#   --direct      start the processes here instead of through scripts/launch_swarm.sh
#
# Experiments run one after another (one line of progress each): the four shapes, the repulsion study,
# tracking on both paths without and with feed-forward and around a fixed centre, then simulator-only
# studies of the published law's limits. Exit status: 0 when every run completed, 1 otherwise.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
py=/usr/bin/python3 # Debian's python3 with python3-matplotlib (scripts/install_deps.sh)
export PYTHONDONTWRITEBYTECODE=1 # no __pycache__ in scripts/

quick=() build="$root/build" data="" domain=131 backend=auto
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=(--quick); shift ;;
    --build) [ $# -ge 2 ] || { echo "reproduce_paper: --build: missing value" >&2; exit 2; }; build=$2; shift 2 ;;
    --data) [ $# -ge 2 ] || { echo "reproduce_paper: --data: missing value" >&2; exit 2; }; data=$2; shift 2 ;;
    --domain) [ $# -ge 2 ] || { echo "reproduce_paper: --domain: missing value" >&2; exit 2; }; domain=$2; shift 2 ;;
    --direct) backend=direct; shift ;;
    -h|--help) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
    *) echo "reproduce_paper: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ $domain =~ ^[0-9]+$ ]] && [ "$domain" -le 224 ] || { echo "reproduce_paper: --domain: expected 0..224, got '$domain'" >&2; exit 2; }
case "$build" in /*) ;; *) build="$PWD/$build" ;; esac
[ -n "$data" ] || data="$build/paper"
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
"$py" "$root/scripts/paper_experiments.py" run --build "$build" --data "$data" --domain "$domain" \
  --backend "$backend" "${quick[@]}" || status=1
"$py" "$root/scripts/plot_paper.py" --data "$data" --out "$root/docs/figures"
"$py" "$root/scripts/paper_experiments.py" report --data "$data" --results "$root/docs/RESULTS.md" \
  --figures "$root/docs/figures"
echo "reproduce_paper: done in $(($(date +%s) - start)) s; figures in docs/figures/paper_*.png, table in docs/RESULTS.md, data in $data"
exit $status
