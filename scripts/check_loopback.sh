#!/usr/bin/env bash
# Runs a command while capturing every non-loopback interface for RTPS (DDS) packets, and fails if any
# packet of the project left loopback.
#
#   scripts/check_loopback.sh COMMAND [ARGS...]
#
# Exit status: the command's, or 1 if it passed but RTPS packets were seen off loopback.
# Needs root and tcpdump (scripts/install_deps.sh); without them it runs the command unchecked and says so.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -uo pipefail
[ $# -gt 0 ] || { echo "usage: scripts/check_loopback.sh COMMAND [ARGS...]" >&2; exit 2; }

capdir=$(mktemp -d)
caps=()
if [ "$(id -u)" -eq 0 ] && command -v tcpdump >/dev/null && command -v ip >/dev/null; then
  for ifc in $(ip -o link show | awk -F': ' '{print $2}' | cut -d@ -f1 | grep -v '^lo$'); do
    # RTPS packets start with the magic "RTPS" (0x52545053) right after the UDP header.
    tcpdump -i "$ifc" -n -p -U -w "$capdir/$ifc.pcap" 'udp and udp[8:4] = 0x52545053' >/dev/null 2>&1 &
    caps+=($!)
  done
  sleep 1
  echo "check_loopback: capturing RTPS on: $(ls "$capdir" | sed 's/\.pcap$//' | tr '\n' ' ')" >&2
else
  echo "check_loopback: not root or no tcpdump/ip: running WITHOUT the off-loopback capture" >&2
fi

"$@"
status=$?

if [ ${#caps[@]} -gt 0 ]; then
  sleep 1
  kill "${caps[@]}" 2>/dev/null
  wait "${caps[@]}" 2>/dev/null
  leaked=0
  for f in "$capdir"/*.pcap; do
    n=$(tcpdump -r "$f" -n 2>/dev/null | wc -l)
    if [ "$n" -gt 0 ]; then
      echo "check_loopback: FAIL: $n RTPS packets left loopback on $(basename "$f" .pcap):" >&2
      tcpdump -r "$f" -n 2>/dev/null | head -5 >&2
      leaked=1
    fi
  done
  if [ $leaked -eq 0 ]; then
    echo "check_loopback: no RTPS packet left loopback" >&2
  elif [ $status -eq 0 ]; then
    status=1
  fi
fi
rm -rf "$capdir"
exit $status
