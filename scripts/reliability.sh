#!/usr/bin/env bash
# Measures how the swarm goes through faults and writes the tables of docs/RELIABILITY.md.
#
#   scripts/reliability.sh [--runs R] [--quick] [--only FAULT[,FAULT...]] [--laws paper,arc]
#                          [--losses 0,10,20,40] [--out FILE] [--build DIR] [--dry-run] [--help-all]
#
#   --runs R     runs per row (default 5): median and worst of R runs
#   --quick      a smoke run: the arc law, losses 0 and 20 %, stalls of 5 s; writes no document
#                unless --out is given
#   --only F,..  faults among loss, partition, kill, pause, supervisor (on a LAN of namespace test
#                hosts: needs root) and stall (loopback); default all
#   --out FILE   the document whose generated tables are replaced (default docs/RELIABILITY.md)
#   --build DIR  build folder holding bin/ (default build)
#   --dry-run    print the plan and its estimated duration; start nothing
#   --help-all   every option of the driver (scripts/reliability.py)
#
# For each fault, law and loss level: time to detect (an agent dropped), time to recover (the swarm
# whole and converged again), samples lost, processes aborted, recording complete; docs/RELIABILITY.md
# ("Faults on a LAN") defines each. Progress on stderr; every run in runs/<UTC time>-reliability/.
# Run it alone on the machine: the numbers are timings (the load average is recorded with them).
# Exit status: 0 ok, 1 cannot run (not root, not built), 2 bad arguments.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
driver="$root/scripts/reliability.py"
[ "${1-}" = --help-all ] && exec python3 "$driver" --help

# The arguments first (exit 2 without starting anything), then root and the build.
python3 "$driver" --dry-run "$@" >/dev/null || exit $?
case " $* " in *" --dry-run "*) exec python3 "$driver" "$@" ;; esac
args=("$@") build="$root/build" only=""
while [ $# -gt 0 ]; do
  case "$1" in --build) build=${2-}; shift ;; --only) only=${2-}; shift ;; esac
  shift
done
if [ "$only" != stall ] && [ "$(id -u)" -ne 0 ]; then
  echo "reliability: the LAN faults need root (network namespaces); run as root, or --only stall" >&2
  exit 1
fi
for exe in shapeform_agent shapeform_supervisor shapeform_echo; do
  [ -x "$build/bin/$exe" ] || { echo "reliability: $build/bin/$exe not found: scripts/build.sh first" >&2; exit 1; }
done
exec python3 "$driver" "${args[@]}"
