#!/usr/bin/env bash
# Test hosts on this machine: K Linux network namespaces on one private bridge, and faults on them.
#
#   scripts/netlab.sh up LAB K [--subnet A.B.C]   make hosts LAB-h1..LAB-hK (addresses A.B.C.1..K)
#   scripts/netlab.sh down LAB                    stop every process on them, remove all of LAB
#   scripts/netlab.sh exec LAB HOST CMD [ARG...]  run CMD on host HOST (h1..hK) of LAB
#   scripts/netlab.sh fault LAB HOST loss PCT     drop PCT % (0..100) of UDP datagrams in and out
#   scripts/netlab.sh fault LAB HOST partition    drop all traffic in and out of HOST
#   scripts/netlab.sh fault LAB HOST nomulticast  drop multicast (224.0.0.0/4) in and out of HOST
#   scripts/netlab.sh fault LAB HOST heal         remove HOST's loss, partition or nomulticast
#   scripts/netlab.sh pause LAB HOST [PID]        SIGSTOP PID, or every process on HOST
#   scripts/netlab.sh resume LAB HOST [PID]       SIGCONT PID, or every process on HOST
#   scripts/netlab.sh show [LAB]                  the labs, hosts, addresses, faults, processes
#
# LAB is a short name (letters, digits; at most 8 characters). Every host is the namespace
# `sf-LAB-hN` with `lo`, `eth0` (A.B.C.N/24 on the lab's bridge, multicast routed on it) and `eth1`
# (A.B.(C+1).N/24 on a second bridge: "another interface" that the lan profile must leave alone). Both
# bridges live in the namespace `sf-LAB-sw`, which has no other link: no packet of a lab reaches this
# machine's own interfaces or any other network. The default subnet is 10.200.C with C derived from
# LAB. Faults are iptables rules in the host's own chain `SHAPEFORM` (packets on eth0 only; traffic
# between processes of one host is never dropped). `down` is idempotent and removes only what `up`
# recorded in /run/shapeform-netlab/LAB (namespaces, and with them their links, bridges and rules).
# Needs root, iproute2 and iptables (scripts/install_deps.sh). Exit status: 0 ok, 1 failure, 2 bad usage.
case "${1-}" in -h|--help|"") awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; [ -n "${1-}" ]; exit $? ;; esac
set -uo pipefail

readonly prog=netlab state_root=/run/shapeform-netlab
die() { echo "$prog: $*" >&2; exit 2; }
fail() { echo "$prog: $*" >&2; exit 1; }

lab_ok() { [[ $1 =~ ^[a-z0-9]{1,8}$ ]] || die "LAB: expected 1..8 lowercase letters or digits, got '${1:0:40}'"; }
need_root() {
  [ "$(id -u)" -eq 0 ] || fail "needs root (network namespaces and iptables)"
  command -v ip >/dev/null || fail "ip (iproute2) not found: run scripts/install_deps.sh"
  command -v iptables >/dev/null || fail "iptables not found: run scripts/install_deps.sh"
}
ns_exists() { ip netns list | awk '{print $1}' | grep -qx -- "$1"; }
in_ns() { local ns=$1; shift; ip netns exec "$ns" "$@"; }
state_file() { echo "$state_root/$1"; }
hosts_of() { [ -f "$(state_file "$1")" ] && awk '$1 == "host" { print $2 }' "$(state_file "$1")"; }
host_ns() { # LAB HOST -> namespace name, checked
  [[ $2 =~ ^h[0-9]+$ ]] || die "HOST: expected h1..hK, got '${2:0:40}'"
  hosts_of "$1" | grep -qx -- "$2" || die "HOST: no host '$2' in lab '$1' (scripts/netlab.sh show $1)"
  echo "sf-$1-$2"
}
default_subnet() { # LAB -> 10.200.C with C even in 2..250, from a hash of LAB
  local h
  h=$(printf '%s' "$1" | cksum | awk '{print $1}')
  echo "10.200.$((2 + (h % 125) * 2))"
}

# ------------------------------------------------------------------------------------------------
cmd_up() {
  local lab=${1-} k=${2-} subnet="" i ns sw file other
  lab_ok "$lab"
  [[ $k =~ ^[0-9]+$ ]] && [ "$k" -ge 1 ] && [ "$k" -le 32 ] || die "K: expected 1..32 hosts, got '${k:0:40}'"
  shift 2
  while [ $# -gt 0 ]; do
    case "$1" in
      --subnet) [[ ${2-} =~ ^10\.([0-9]{1,3})\.([0-9]{1,3})$ ]] && [ "${BASH_REMATCH[1]}" -le 255 ] &&
                  [ "${BASH_REMATCH[2]}" -le 254 ] || die "--subnet: expected 10.B.C (C <= 254), got '${2-}'"
                subnet=$2; shift 2 ;;
      *) die "up: unknown argument '${1:0:40}'" ;;
    esac
  done
  need_root
  [ -n "$subnet" ] || subnet=$(default_subnet "$lab")
  other="${subnet%.*}.$((${subnet##*.} + 1))"
  file=$(state_file "$lab")
  [ ! -e "$file" ] || fail "lab '$lab' exists already (scripts/netlab.sh down $lab first)"
  sw="sf-$lab-sw"
  for ((i = 1; i <= k; i++)); do ns_exists "sf-$lab-h$i" && fail "namespace sf-$lab-h$i exists but is not ours"; done
  ns_exists "$sw" && fail "namespace $sw exists but is not ours"
  mkdir -p "$state_root"
  echo "subnet $subnet $other" >"$file"
  # Record each namespace before creating it: a failure half-way still leaves `down` a full list.
  trap 'echo "$prog: up failed; removing what it made" >&2; cmd_down "$lab" >/dev/null 2>&1; exit 1' ERR
  set -E
  echo "switch $sw" >>"$file"
  ip netns add "$sw"
  in_ns "$sw" ip link set lo up
  in_ns "$sw" sysctl -q -w net.ipv6.conf.all.disable_ipv6=1 net.ipv6.conf.default.disable_ipv6=1
  for br in br0 br1; do
    in_ns "$sw" ip link add "$br" type bridge
    # Multicast floods to every port (no snooping): the test LAN behaves as a plain switch.
    in_ns "$sw" ip link set "$br" type bridge mcast_snooping 0
    in_ns "$sw" ip link set "$br" up
  done
  for ((i = 1; i <= k; i++)); do
    ns="sf-$lab-h$i"
    echo "host h$i $ns $subnet.$i $other.$i" >>"$file"
    ip netns add "$ns"
    in_ns "$ns" ip link set lo up
    # IPv4 only: no IPv6 link-local chatter on the test LAN.
    in_ns "$ns" sysctl -q -w net.ipv6.conf.all.disable_ipv6=1 net.ipv6.conf.default.disable_ipv6=1
    for j in 0 1; do
      ip link add "eth$j" netns "$ns" type veth peer name "h$i-$j" netns "$sw"
      in_ns "$sw" ip link set "h$i-$j" master "br$j"
      in_ns "$sw" ip link set "h$i-$j" up
    done
    in_ns "$ns" ip addr add "$subnet.$i/24" dev eth0
    in_ns "$ns" ip addr add "$other.$i/24" dev eth1
    in_ns "$ns" ip link set eth0 up
    in_ns "$ns" ip link set eth1 up
    in_ns "$ns" ip route add 224.0.0.0/4 dev eth0
    in_ns "$ns" iptables -N SHAPEFORM
    in_ns "$ns" iptables -A INPUT -j SHAPEFORM
    in_ns "$ns" iptables -A OUTPUT -j SHAPEFORM
  done
  trap - ERR
  echo "$prog: lab $lab up: $k hosts sf-$lab-h1..h$k on $subnet.0/24 (eth0), $other.0/24 (eth1)" >&2
}

# Stops every process in a namespace: SIGCONT (a paused one must see its SIGTERM), SIGTERM, up to 5 s,
# then SIGKILL; waits until none is left.
stop_ns_processes() {
  local ns=$1 pids i
  pids=$(ip netns pids "$ns" 2>/dev/null | tr '\n' ' ')
  [ -n "${pids// /}" ] || return 0
  kill -CONT $pids 2>/dev/null
  kill -TERM $pids 2>/dev/null
  for ((i = 0; i < 50; i++)); do
    pids=$(ip netns pids "$ns" 2>/dev/null | tr '\n' ' ')
    [ -n "${pids// /}" ] || return 0
    sleep 0.1
  done
  echo "$prog: $ns: processes $pids ignored SIGTERM for 5 s: SIGKILL" >&2
  kill -KILL $pids 2>/dev/null
  for ((i = 0; i < 50; i++)); do
    [ -n "$(ip netns pids "$ns" 2>/dev/null)" ] || return 0
    sleep 0.1
  done
  echo "$prog: $ns: processes still running after SIGKILL: $(ip netns pids "$ns" | tr '\n' ' ')" >&2
  return 1
}

cmd_down() {
  local lab=${1-} file ns rc=0
  lab_ok "$lab"
  need_root
  file=$(state_file "$lab")
  [ -f "$file" ] || return 0
  # Hosts first (their processes, then the namespace: its veths, rules and routes go with it).
  for ns in $(awk '$1 == "host" { print $3 }' "$file") $(awk '$1 == "switch" { print $2 }' "$file"); do
    ns_exists "$ns" || continue
    stop_ns_processes "$ns" || rc=1
    ip netns delete "$ns" || rc=1
  done
  [ $rc -eq 0 ] && rm -f "$file"
  [ $rc -eq 0 ] && echo "$prog: lab $lab down" >&2
  return $rc
}

cmd_exec() {
  local lab=${1-} host=${2-} ns
  lab_ok "$lab"
  [ $# -ge 3 ] || die "exec: usage: exec LAB HOST CMD [ARG...]"
  need_root
  ns=$(host_ns "$lab" "$host") || exit $?
  shift 2
  exec ip netns exec "$ns" "$@"
}

cmd_fault() {
  local lab=${1-} host=${2-} what=${3-} ns p
  lab_ok "$lab"
  need_root
  ns=$(host_ns "$lab" "$host") || exit $?
  case "$what" in
    loss)
      [[ ${4-} =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v v="$4" 'BEGIN{exit !(v <= 100)}' ||
        die "loss: expected a percentage 0..100, got '${4-}'"
      p=$(awk -v v="$4" 'BEGIN{printf "%.4f", v / 100}')
      in_ns "$ns" iptables -F SHAPEFORM || exit 1
      in_ns "$ns" iptables -A SHAPEFORM -i eth0 -p udp -m statistic --mode random --probability "$p" -j DROP &&
        in_ns "$ns" iptables -A SHAPEFORM -o eth0 -p udp -m statistic --mode random --probability "$p" -j DROP ||
        exit 1 ;;
    partition)
      in_ns "$ns" iptables -F SHAPEFORM || exit 1
      in_ns "$ns" iptables -A SHAPEFORM -i eth0 -j DROP && in_ns "$ns" iptables -A SHAPEFORM -o eth0 -j DROP || exit 1 ;;
    nomulticast) # a network that carries no multicast (the rules' counters tell what was dropped)
      in_ns "$ns" iptables -F SHAPEFORM || exit 1
      in_ns "$ns" iptables -A SHAPEFORM -i eth0 -d 224.0.0.0/4 -j DROP &&
        in_ns "$ns" iptables -A SHAPEFORM -o eth0 -d 224.0.0.0/4 -j DROP || exit 1 ;;
    heal) in_ns "$ns" iptables -F SHAPEFORM || exit 1 ;;
    *) die "fault: expected loss PCT, partition, nomulticast or heal, got '${what:0:40}'" ;;
  esac
}

cmd_signal() { # SIG LAB HOST [PID]
  local sig=$1 lab=${2-} host=${3-} pid=${4-} ns pids
  lab_ok "$lab"
  need_root
  ns=$(host_ns "$lab" "$host") || exit $?
  pids=$(ip netns pids "$ns" | tr '\n' ' ')
  if [ -n "$pid" ]; then
    [[ " $pids " == *" $pid "* ]] || die "PID: $pid is not a process on $lab $host"
    pids=$pid
  fi
  [ -n "${pids// /}" ] || return 0
  kill "-$sig" $pids
}

cmd_show() {
  local only=${1-} file lab
  [ -n "$only" ] && lab_ok "$only"
  for file in "$state_root"/*; do
    [ -f "$file" ] || continue
    lab=$(basename "$file")
    [ -z "$only" ] || [ "$lab" = "$only" ] || continue
    echo "lab $lab"
    awk '$1 == "host" { print $2, $3, $4, $5 }' "$file" | while read -r host ns a b; do
      local rules procs
      rules=$(ip netns exec "$ns" iptables -S SHAPEFORM 2>/dev/null | grep -c '^-A' || true)
      procs=$(ip netns pids "$ns" 2>/dev/null | wc -l)
      echo "  $host $ns eth0 $a eth1 $b fault-rules $rules processes $procs"
    done
  done
}

case "$1" in
  up) shift; cmd_up "$@" ;;
  down) shift; cmd_down "$@" ;;
  exec) shift; cmd_exec "$@" ;;
  fault) shift; cmd_fault "$@" ;;
  pause) shift; cmd_signal STOP "$@" ;;
  resume) shift; cmd_signal CONT "$@" ;;
  show) shift; cmd_show "$@" ;;
  *) die "unknown command '${1:0:40}' (see --help)" ;;
esac
