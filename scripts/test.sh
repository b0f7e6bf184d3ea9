#!/usr/bin/env bash
# Runs every test: installs dependencies, configures (warnings as errors), builds, runs ctest.
# While the tests run, every non-loopback interface is captured for RTPS packets: any packet of the
# project leaving loopback fails the run. The exit status is the tests'.
set -uo pipefail
cd "$(dirname "$0")/.."
./scripts/build.sh -DSHAPEFORM_WERROR=ON || exit 1

capdir=$(mktemp -d)
caps=()
if [ "$(id -u)" -eq 0 ] && command -v tcpdump >/dev/null; then
  for ifc in $(ip -o link show | awk -F': ' '{print $2}' | cut -d@ -f1 | grep -v '^lo$'); do
    # RTPS packets start with the magic "RTPS" (0x52545053) right after the UDP header.
    tcpdump -i "$ifc" -n -p -U -w "$capdir/$ifc.pcap" 'udp and udp[8:4] = 0x52545053' >/dev/null 2>&1 &
    caps+=($!)
  done
  sleep 1
  echo "test.sh: capturing RTPS on non-loopback interfaces: $(ls "$capdir" | sed 's/.pcap//' | tr '\n' ' ')"
else
  echo "test.sh: not root or no tcpdump: the off-loopback capture is skipped (the tests still run)"
fi

ctest --test-dir build --output-on-failure --timeout 900 -j2 "$@"
status=$?

if [ ${#caps[@]} -gt 0 ]; then
  sleep 1
  kill "${caps[@]}" 2>/dev/null; wait "${caps[@]}" 2>/dev/null
  leaked=0
  for f in "$capdir"/*.pcap; do
    n=$(tcpdump -r "$f" -n 2>/dev/null | wc -l)
    if [ "$n" -gt 0 ]; then
      echo "test.sh: FAIL: $n RTPS packets left loopback on $(basename "$f" .pcap):"
      tcpdump -r "$f" -n 2>/dev/null | head -5
      leaked=1
    fi
  done
  [ $leaked -eq 0 ] && echo "test.sh: no RTPS packet left loopback"
  [ $leaked -ne 0 ] && [ $status -eq 0 ] && status=1
fi
rm -rf "$capdir"
exit $status
