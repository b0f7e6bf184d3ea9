#!/usr/bin/env bash
# Launches a swarm of shapeform agent processes and a supervisor running one scenario, on loopback,
# or on the hosts of a fleet file.
#
#   scripts/launch_swarm.sh -n N --scenario NAME [--domain D] [--rate HZ] [--record DIR] [--init CSV]
#                           [--seed S] [--steps K] [--timeout S] [--set key=value]... [--json]
#                           [--build DIR] [--runs DIR] [--view] [--vehicles sim] [--secure [--keystore DIR]]
#   scripts/launch_swarm.sh --fleet FILE --scenario NAME [the same options but -n]
#
#   -n N            number of agent processes, ids 0..N-1 (default: the rows of --init, else the
#                   scenario's swarm.agents); from the min_agents of config/large_swarm.sets on
#                   (50; with --secure from its min_secured_agents, 16), its large-swarm settings
#                   are added before any --set (which win)
#   --scenario NAME config/scenarios/NAME.yaml, or a path to a YAML file
#   --fleet FILE    run on the hosts of a fleet file (config/fleets/*.yaml, format in
#                   config/fleets/README.md): each process on its host with the lan profile bound to the
#                   host's address; test hosts the fleet asks for are made first and removed on exit
#   --domain D      DDS domain id 0..232 (default: 10..100, derived from the PID, skipping domains
#                   in use on this host)
#   --rate HZ       agent loop rate (agent.rate_hz and supervisor.target_rate_hz)
#   --record DIR    record the run into DIR (default: RUN/record; its CSV files and run.mcap: docs/RECORDING.md)
#   --init CSV      agent i starts at row i (x1,x2; optional header); N must equal the row count
#   --seed S        seeded starts: agent i starts where shapeform_sim --seed S puts agent i
#                   (default: the scenario's swarm.seed)
#   --steps K       run exactly K iterations of model time (`wait time K*dt`) instead of waiting
#                   for convergence; the exit status is still the verdict, taken after the K
#                   iterations (`wait converged timeout=0`): 0 converged, 3 not converged
#   --timeout S     seconds to wait for convergence (default 60), or for the K iterations
#   --set key=value config override passed to every process (repeatable)
#   --json          machine output on stdout (progress stays on stderr): first the line
#                   {"event":"run","dir":RUN,"domain":D,"agents":N}, last the supervisor's JSON
#                   summary (its "summary" event)
#   --build DIR     build folder holding bin/ (default: build)
#   --runs DIR      where run folders are made (default: runs)
#   --view          also start shapeform_view (the swarm in a web browser, on 127.0.0.1 and a free
#                   port) beside the supervisor, and print its URL (with --json also the line
#                   {"event":"view","url":URL}); it stops with the run (replay: shapeform_view --replay RUN)
#   --vehicles sim  the agents drive simulated robots: shapeform_vehicle starts before the agents and
#                   hosts their robots (with --fleet one per host that runs agents, hosting that host's
#                   robots), with the same config, --set, domain and seed; every process gets
#                   vehicle.interface=ros2 (robot i starts where agent i would, at its seeded start and
#                   heading; choose the model and its limits with --set vehicle.model=unicycle
#                   --set vehicle.max_speed=1 ...: docs/VEHICLES.md). The robots' poses are recorded in
#                   RECORD/vehicles.csv; the vehicle processes stop after the agents. Not with --init.
#   --secure        DDS Security for every process (security.enabled: authenticated, access-controlled,
#                   encrypted; docs/SECURITY.md), with a new keystore made in RUN/keystore
#                   (scripts/make_keystore.sh RUN/keystore --agents N, and --enclave vehicle with
#                   --vehicles) unless --keystore is given; from min_secured_agents (16) agent
#                   processes on, the large-swarm settings and agents started 0.5 s apart
#                   (docs/SECURITY.md, Cost)
#                   (a fleet with ssh hosts needs --keystore: the keystore must be on every host)
#   --keystore DIR  use this keystore (implies --secure); it must hold the enclaves supervisor,
#                   agent_0..agent_{N-1} (and viewer with --view, vehicle with --vehicles); with ssh hosts,
#                   at the same path on each
#
# One run folder per launch: RUNS/<UTC timestamp>-<scenario>-n<N>/ with agent_<i>.log (stderr),
# agent_<i>.out (the agent's JSON event lines: status, command), supervisor.log (stderr: progress),
# supervisor.out (stdout: answers and summary; JSON event lines with --json), script.txt and record/
# (with --vehicles also vehicle.log and vehicle.out, or vehicle_<host>.log and .out per fleet host; with
# --fleet also fleet.yaml, the file, and fleet.txt, the plan followed; an ssh host's streams come back
# through ssh into these files). Progress goes to stderr. On exit, error or Ctrl-C only this
# launcher's own children are stopped (SIGTERM, then SIGKILL after 5 s; on an ssh host the process
# group it started there), and test hosts it made are removed. Exit status: the supervisor's (0
# converged, 1 runtime failure, 2 bad input, 3 not converged: a wait timed out, or with --steps the
# swarm was not converged after its K iterations); 2 for bad launcher arguments or fleet file;
# 130/143 when interrupted.
set -uo pipefail

readonly prog=launch_swarm
root=$(cd "$(dirname "$0")/.." && pwd)

die() { # message -> one line on stderr, exit 2 (bad input)
  echo "$prog: $*" >&2
  exit 2
}
say() { echo "$prog: $*" >&2; }

usage() { sed -n '2,/^set -uo/{/^set -uo/d;s/^# \{0,1\}//;p}' "$0"; }

is_uint() { [[ $1 =~ ^[0-9]+$ ]]; }
is_posnum() { [[ $1 =~ ^([0-9]+([.][0-9]*)?|[.][0-9]+)([eE][-+]?[0-9]+)?$ ]] && awk -v v="$1" 'BEGIN{exit !(v+0 > 0)}'; }

# ------------------------------------------------------------------------------------------------
# Arguments

n="" scenario="" fleet="" domain="" rate="" record="" init="" seed="" steps="" timeout="" json=0
build="build" runs="runs" view=0 secure=0 keystore="" vehicles=""
sets=()
need_value() { # flag remaining-args value
  [ "$2" -ge 2 ] || die "$1: missing value"
  [[ $3 != --* ]] || die "$1: missing value (got the flag '$3')"
}
while [ $# -gt 0 ]; do
  case "$1" in
    -n|--agents) need_value "$1" $# "${2-}"; n=$2; shift 2 ;;
    --scenario) need_value "$1" $# "${2-}"; scenario=$2; shift 2 ;;
    --fleet) need_value "$1" $# "${2-}"; fleet=$2; shift 2 ;;
    --domain) need_value "$1" $# "${2-}"; domain=$2; shift 2 ;;
    --rate) need_value "$1" $# "${2-}"; rate=$2; shift 2 ;;
    --record) need_value "$1" $# "${2-}"; record=$2; shift 2 ;;
    --init) need_value "$1" $# "${2-}"; init=$2; shift 2 ;;
    --seed) need_value "$1" $# "${2-}"; seed=$2; shift 2 ;;
    --steps) need_value "$1" $# "${2-}"; steps=$2; shift 2 ;;
    --timeout) need_value "$1" $# "${2-}"; timeout=$2; shift 2 ;;
    --set) need_value "$1" $# "${2-}"; sets+=("$2"); shift 2 ;;
    --build) need_value "$1" $# "${2-}"; build=$2; shift 2 ;;
    --runs) need_value "$1" $# "${2-}"; runs=$2; shift 2 ;;
    --json) json=1; shift ;;
    --view) view=1; shift ;;
    --vehicles) need_value "$1" $# "${2-}"; vehicles=$2; shift 2 ;;
    --secure) secure=1; shift ;;
    --keystore) need_value "$1" $# "${2-}"; keystore=$2; secure=1; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done

[ -n "$scenario" ] || die "--scenario: required (one of: $(cd "$root/config/scenarios" && ls ./*.yaml | sed 's|^\./||; s|\.yaml$||' | tr '\n' ' '))"
[ -z "$fleet" ] || [ -z "$n" ] || die "-n: not with --fleet (the fleet file says which agents run where)"
[ -z "$fleet" ] || [ $view -eq 0 ] || die "--view: not with --fleet yet (the view joins on this host's loopback; run shapeform_view on a host of the fleet with --set transport.profile=lan and its address, and --bind an address you can reach)"
if [ -n "$n" ]; then
  { is_uint "$n" && [ "$n" -ge 1 ] && [ "$n" -le 1000 ]; } || die "-n: expected an integer 1..1000, got '$n'"
fi
if [ -n "$domain" ]; then
  { is_uint "$domain" && [ "$domain" -le 232 ]; } || die "--domain: expected an integer 0..232, got '$domain'"
fi
if [ -n "$rate" ]; then
  { is_posnum "$rate" && awk -v v="$rate" 'BEGIN{exit !(v <= 1000)}'; } || die "--rate: expected a number in (0, 1000], got '$rate'"
fi
[ -z "$seed" ] || is_uint "$seed" || die "--seed: expected an integer >= 0, got '$seed'"
case "$vehicles" in
  "" | sim) ;;
  *) die "--vehicles: expected sim (simulated robots: shapeform_vehicle), got '${vehicles:0:60}'" ;;
esac
[ -z "$vehicles" ] || [ -z "$init" ] ||
  die "--init: not with --vehicles sim (the simulated robots start at the seeded starts: give --seed S instead)"
if [ -n "$steps" ]; then
  { is_uint "$steps" && [ "$steps" -ge 1 ]; } || die "--steps: expected an integer >= 1, got '$steps'"
fi
[ -z "$timeout" ] || is_posnum "$timeout" || die "--timeout: expected a number of seconds > 0, got '$timeout'"
for s in "${sets[@]+"${sets[@]}"}"; do
  [[ $s == ?*=* ]] || die "--set: expected key=value, got '$s'"
  if [ -n "$vehicles" ] && [[ $s == vehicle.interface=* ]] && [ "${s#*=}" != ros2 ]; then
    die "--set $s: not with --vehicles sim (the agents drive the simulated robots over ROS 2 topics: drop this --set)"
  fi
done
if [ -n "$init" ]; then [ -r "$init" ] && [ -f "$init" ] || die "--init: cannot read '$init'"; fi
if [ $secure -eq 1 ] && [ -z "$keystore" ] && [ -n "$fleet" ] && grep -qE 'run: *ssh' "$fleet"; then
  die "--secure: the fleet has ssh hosts: make a keystore (scripts/make_keystore.sh DIR --agents N), copy it to the same path on every host and give --keystore DIR"
fi
if [ -n "$keystore" ]; then
  [ -d "$keystore/enclaves" ] || die "--keystore: '${keystore:0:200}' is no keystore (no enclaves/ folder): make one with scripts/make_keystore.sh DIR --agents N"
  keystore=$(cd "$keystore" && pwd)
fi
# An output folder is checked before anything starts (the supervisor checks --record too, but only once
# the launcher has started the agents beside it): created as the recorder would, and a file written in it.
writable_dir() { # dir -> 0 when a file can be created in it (root included: a probe, not permissions)
  local probe
  mkdir -p -- "$1" 2>/dev/null && probe=$(mktemp -- "$1/.shapeform_write_probe_XXXXXX" 2>/dev/null) &&
    rm -f -- "$probe"
}
if [ -n "$record" ]; then
  writable_dir "$record" || die "--record: cannot write into the folder '${record:0:200}': give a writable folder"
fi

case "$build" in /*) ;; *) build="$root/$build" ;; esac
case "$runs" in /*) ;; *) runs="$root/$runs" ;; esac
bin="$build/bin"
for exe in shapeform_agent shapeform_supervisor shapeform_sim ${vehicles:+shapeform_vehicle}; do
  [ -x "$bin/$exe" ] || die "--build: $bin/$exe not found (run ./scripts/build.sh first)"
done

if [ -f "$scenario" ]; then
  config=$(cd "$(dirname "$scenario")" && pwd)/$(basename "$scenario")
elif [ -f "$root/config/scenarios/$scenario.yaml" ]; then
  config="$root/config/scenarios/$scenario.yaml"
else
  die "--scenario: no scenario '$scenario' (one of: $(cd "$root/config/scenarios" && ls ./*.yaml | sed 's|^\./||; s|\.yaml$||' | tr '\n' ' ')or a path to a .yaml file)"
fi
name=$(basename "$config" .yaml)

# ------------------------------------------------------------------------------------------------
# Fleet: read once by scripts/lib/fleet.py (a bad file is one line naming the key, exit 2). Without
# --fleet every process runs here, on the host "" (plain commands, the configuration's own transport).

declare -A host_addr=() host_kind=() host_target=()
hosts=() agent_host=() sup_host="" fleet_name="" fleet_peers="" lab=() lab_made=""
fleet_discovery="" fleet_addresses=""
if [ -n "$fleet" ]; then
  [ -f "$fleet" ] && [ -r "$fleet" ] || die "--fleet: cannot read '${fleet:0:200}'"
  fleet=$(cd "$(dirname "$fleet")" && pwd)/$(basename "$fleet")
  /usr/bin/python3 -c 'import yaml' 2>/dev/null ||
    die "--fleet: reading fleet files needs /usr/bin/python3 with python3-yaml (scripts/install_deps.sh)"
  plan=$(/usr/bin/python3 "$root/scripts/lib/fleet.py" "$fleet" --prog "$prog: --fleet") || exit 2
  while read -r what a b c d; do
    case "$what" in
      fleet) fleet_name=$a; n=$b ;;
      lab) lab=("$a" "$b" "$c") ;;
      discovery) fleet_discovery=$a; fleet_addresses=$b ;;
      host) hosts+=("$a"); host_addr[$a]=$b; host_kind[$a]=$c; host_target[$a]=$d ;;
      agent) agent_host[$a]=$b ;;
      supervisor) sup_host=$a ;;
    esac
  done <<<"$plan"
  for h in "${hosts[@]}"; do
    [ "${host_kind[$h]}" = netns ] || continue
    [ "$(id -u)" -eq 0 ] || die "--fleet: host $h runs in the network namespace ${host_target[$h]}: needs root"
    [ ${#lab[@]} -gt 0 ] && [[ ${host_target[$h]} == sf-${lab[0]}-h* ]] && continue
    ip netns list 2>/dev/null | awk '{print $1}' | grep -qx -- "${host_target[$h]}" ||
      die "--fleet: host $h: no network namespace ${host_target[$h]} on this machine"
  done
  [ ${#lab[@]} -eq 0 ] || [ "$(id -u)" -eq 0 ] || die "--fleet: lab: making test hosts needs root"
  if [ ${#lab[@]} -gt 0 ] && [ -e "/run/shapeform-netlab/${lab[0]}" ]; then
    die "--fleet: lab.name: the test hosts '${lab[0]}' exist already (made by another run?): scripts/netlab.sh down ${lab[0]}"
  fi
  # Unicast discovery to every host when the file asks for it, and always when secured: security
  # refuses multicast discovery (Fast DDS 2.9.1 can leave pairs that discover each other at the same
  # moment unable to authenticate: docs/SECURITY.md, Deploying on real hosts).
  if [ "$fleet_discovery" = unicast ] || [ $secure -eq 1 ]; then fleet_peers=$fleet_addresses; fi
fi
on_ssh() { [ -n "$1" ] && [ "${host_kind[$1]}" = ssh ]; }
# The --set flags of a process on host $1 (the lan profile bound to the host's address), in hsets.
host_sets() {
  hsets=()
  [ -n "$1" ] || return 0
  hsets=(--set transport.profile=lan --set "transport.interfaces=[${host_addr[$1]}]")
  [ -z "$fleet_peers" ] || hsets+=(--set "transport.peers=[$fleet_peers]")
}

# ------------------------------------------------------------------------------------------------
# Validate the whole configuration once, with the simulator (0 steps): the same loader and checks
# as the processes, so a bad --set or --init is one clear message and nothing starts.

[ -n "$rate" ] && sets+=("agent.rate_hz=$rate" "supervisor.target_rate_hz=$rate")
[ -n "$vehicles" ] && sets+=("vehicle.interface=ros2")
simargs=(--config "$config" --steps 0 --verbose)
[ -n "$seed" ] && simargs+=(--seed "$seed")
[ -n "$init" ] && simargs+=(--init "$init")
for s in "${sets[@]+"${sets[@]}"}"; do simargs+=(--set "$s"); done
host_sets "$sup_host"
simargs+=("${hsets[@]+"${hsets[@]}"}")
simerr=$(mktemp)
simout=$("$bin/shapeform_sim" "${simargs[@]}" 2>"$simerr")
simrc=$?
if [ $simrc -ne 0 ]; then
  grep '^shapeform_sim: ' "$simerr" | sed "s/^shapeform_sim: /$prog: /" >&2
  rm -f "$simerr"
  exit 2
fi
effective=$(cat "$simerr")
rm -f "$simerr"

json_num() { printf '%s' "$simout" | grep -o "\"$1\":[-0-9.eE+]*" | head -1 | cut -d: -f2; }
yaml_key() { # section key -> value from the effective configuration
  printf '%s\n' "$effective" | awk -v sec="$1:" -v key="$2:" '
    /^[^ #]/ { insec = ($1 == sec) } insec && $1 == key { print $2; exit }'
}
cfg_agents=$(json_num agents)
cfg_seed=$(json_num seed)
dt=$(json_num dt)
rate_eff=$(yaml_key agent rate_hz)
[ -n "$rate_eff" ] || rate_eff=50

starts=()
if [ -n "$init" ]; then
  mapfile -t starts < <(printf '%s' "$simout" | grep -o '"final_positions":\[[^"]*\]\]' |
    sed 's/^"final_positions":\[//; s/\]$//; s/\],\[/\n/g; s/[][]//g')
  if [ -z "$n" ]; then
    n=${#starts[@]}
  elif [ "$n" -ne ${#starts[@]} ]; then
    die "--init: $init has ${#starts[@]} positions but -n is $n"
  fi
fi
[ -n "$n" ] || n=$cfg_agents
[ -n "$seed" ] || seed=$cfg_seed
# N agents, the supervisor and the vehicle process (--vehicles) each take one of the domain's
# participant slots on their host.
max_participants=$(yaml_key transport max_participants)
nveh=0
[ -n "$vehicles" ] && nveh=1
if [ -n "$max_participants" ] && [ -n "$fleet" ]; then
  for h in "${hosts[@]}"; do
    k=0
    for i in "${!agent_host[@]}"; do [ "${agent_host[$i]}" = "$h" ] && k=$((k + 1)); done
    [ $k -gt 0 ] && k=$((k + nveh))
    [ "$sup_host" = "$h" ] && k=$((k + 1))
    [ "$k" -le "$max_participants" ] ||
      die "--fleet: host $h runs $k processes, transport.max_participants is $max_participants (--set transport.max_participants=$k or more)"
  done
elif [ -n "$max_participants" ] && [ $((n + 1 + nveh)) -gt "$max_participants" ]; then
  die "-n $n: $n agents, the supervisor$([ $nveh -eq 1 ] && echo " and the vehicle process") need $((n + 1 + nveh)) participants on this host, transport.max_participants is $max_participants (--set transport.max_participants=$((n + 1 + nveh)) or more)"
fi
# A large swarm on this host: the settings of config/large_swarm.sets first, so the user's --set win.
large_min=$(sed -n 's/^min_agents=//p' "$root/config/large_swarm.sets")
# A secured swarm needs them earlier: Fast DDS 2.9.1 sends every key-exchange message to every
# authenticated participant (docs/SECURITY.md, Cost).
[ $secure -eq 1 ] && large_min=$(sed -n 's/^min_secured_agents=//p' "$root/config/large_swarm.sets")
if [ -z "$fleet" ] && [ "$n" -ge "$large_min" ]; then
  mapfile -t large < <(grep -E '^[a-z_]+\.[a-z_.]+=' "$root/config/large_swarm.sets")
  sets=("${large[@]}" "${sets[@]+"${sets[@]}"}")
  say "$n agents: the large-swarm settings of config/large_swarm.sets (${large[*]})"
fi
# The paper's gains were chosen for its 12 agents: from about 20 its law rests off the shape
# (docs/RESULTS.md), and a run waiting for convergence waits in vain.
[ "$(yaml_key dynamics law)" != paper ] || [ "$n" -lt 20 ] ||
  say "note: $n agents with the paper's law: its gains (dynamics.k1, k2, sigma, beta, r) are the paper's" \
    "for 12 agents, and 20 agents on its circle rest inside the shape (shape error about 0.65, docs/RESULTS.md)," \
    "so the run may not converge; the arc law (dynamics.law=arc, e.g. --scenario arc_circle) spaces any N on the shape"
# Every process sees the swarm size, so seeded starts match shapeform_sim --agents N --seed S.
sets+=("swarm.agents=$n")
setargs=()
for s in "${sets[@]}"; do setargs+=(--set "$s"); done

# ------------------------------------------------------------------------------------------------
# Domain: a free one derived from the PID unless given (a domain is in use when one of the first
# participants' ports, 7400 + 250 d + {0, 10, 12, 14}, is bound on this host).

domain_busy() {
  local d=$1 off hex
  for off in 0 10 12 14; do
    hex=$(printf '%04X' $((7400 + 250 * d + off)))
    grep -qE "^ *[0-9]+: [0-9A-F]+:$hex " /proc/net/udp /proc/net/udp6 2>/dev/null && return 0
  done
  return 1
}
# Derived domains are 10..100: the integration tests use 101..146 and the DDS unit tests 150..229.
if [ -z "$domain" ]; then
  d0=$(($$ % 91))
  for ((k = 0; k < 91; k++)); do
    domain=$(((d0 + k) % 91 + 10))
    domain_busy "$domain" || break
  done
  domain_note="derived from the PID; --domain D to choose"
else
  domain_note="given"
  domain_busy "$domain" && say "warning: domain $domain looks in use by another DDS program on this host"
fi

# ------------------------------------------------------------------------------------------------
# Run folder and script

stamp=$(date -u +%Y%m%dT%H%M%SZ)
writable_dir "$runs" || die "--runs: cannot write into the folder '${runs:0:200}': give a writable folder"
run="$runs/$stamp-$name-n$n"
k=1
while ! mkdir "$run" 2>/dev/null; do
  k=$((k + 1))
  run="$runs/$stamp-$name-n$n-$k"
  [ $k -lt 100 ] || die "--runs: cannot create a run folder in '$runs'"
done
if [ -z "$record" ]; then
  record="$run/record"
else
  case "$record" in /*) ;; *) record="$PWD/$record" ;; esac
fi

if [ -n "$fleet" ]; then
  cp -- "$fleet" "$run/fleet.yaml"
  printf '%s\n' "$plan" >"$run/fleet.txt"
fi

# DDS Security: every process of the run with the same keystore, each with its role's enclave.
if [ $secure -eq 1 ]; then
  if [ -z "$keystore" ]; then
    keystore="$run/keystore"
    kargs=(--agents "$n")
    [ -n "$vehicles" ] && kargs+=(--enclave supervisor --enclave viewer --enclave vehicle)
    "$root/scripts/make_keystore.sh" "$keystore" "${kargs[@]}" >&2 || die "--secure: making the keystore failed"
  fi
  needed=(supervisor)
  [ $view -eq 1 ] && needed+=(viewer)
  [ -n "$vehicles" ] && needed+=(vehicle)
  for ((i = 0; i < n; i++)); do needed+=("agent_$i"); done
  for e in "${needed[@]}"; do
    [ -d "$keystore/enclaves/$e" ] ||
      die "--keystore: no enclave $e in $keystore (add the missing ones: scripts/make_keystore.sh $keystore --agents $n$(
        [ -n "$vehicles" ] && printf ' --enclave %s' "${needed[@]:0:${#needed[@]}-n}"))"
  done
  setargs+=(--set security.enabled=true --set "security.keystore=$keystore")
  # Measured (docs/SECURITY.md, Cost, scripts/secure_mesh.py; with the large-swarm settings and the 0.5 s
  # pacing, which a secured swarm gets from min_secured_agents on): 25 processes meshed in 17-32 s,
  # 50 not within 70 s (key exchange N^3, announcements to every slot at each discovery), while 1000
  # agents in 20 group processes meshed in 8 s.
  [ "$n" -le 25 ] || say "warning: $n secured agent processes: with DDS Security, Fast DDS 2.9.1 sends every" \
    "key-exchange message to every participant; on a 2-core host 25 processes meshed in 17-32 s and 50 did" \
    "not within 70 s (docs/SECURITY.md, Cost); host several agents per process (shapeform_agent_group:" \
    "1000 agents in 20 secured processes meshed in 8 s) or spread them over hosts (--fleet)"
  [ -z "$fleet" ] || [ "$fleet_discovery" = unicast ] || say "secured: discovery by unicast to the fleet's" \
    "hosts ($fleet_peers) instead of the fleet file's multicast (docs/SECURITY.md, Deploying on real hosts)"
fi

agents_timeout=$((30 + n / 2))
# Agents start this many seconds apart. A secured swarm from min_secured_agents on: 0.5 s, so that each
# newcomer's handshakes and key exchange end before the next one's begin; measured with
# scripts/secure_mesh.py, 25 processes meshed in 17-19 s paced against 43-44 s at once (docs/SECURITY.md).
agent_interval=0.02
[ $secure -eq 1 ] && [ -z "$fleet" ] && [ "$n" -ge "$large_min" ] && agent_interval=0.5
# A secured swarm of many processes meshes in tens of seconds (docs/SECURITY.md, Cost: 25 processes in
# 20 to 55 s on a loaded 2-core host): wait for it before commanding a half-meshed swarm.
[ $secure -eq 1 ] && agents_timeout=$((30 + 3 * n))
{
  echo "# generated by scripts/launch_swarm.sh"
  echo "wait agents $n timeout=$agents_timeout"
  echo "start"
  if [ -n "$steps" ]; then
    model_t=$(awk -v k="$steps" -v dt="$dt" 'BEGIN{printf "%.10g", k * dt}')
    wt=${timeout:-$(awk -v k="$steps" -v r="$rate_eff" 'BEGIN{printf "%d", 2 * k / r + 30}')}
    echo "wait time $model_t timeout=$wt"
    # The verdict after the K iterations, as it stands: the exit status is 3 unless converged.
    echo "wait converged timeout=0"
  else
    echo "wait converged timeout=${timeout:-60}"
  fi
  echo "status"
  echo "quit"
} >"$run/script.txt"

# ------------------------------------------------------------------------------------------------
# Children and cleanup

sup_pid="" tail_pids=() agent_pids=() ssh_agent_pids=() view_pid=""
vehicle_pids=() vehicle_procs=() vehicle_hosts=() ssh_vehicle_pids=() # --vehicles: one process per host
interrupted=""
shm_list() { ls /dev/shm 2>/dev/null | grep -E '^(sem\.)?(fastrtps|fast_datasharing|fastdds)' | sort; }
shm_before=$(shm_list)

alive() { kill -0 "$1" 2>/dev/null; }
# Stops the given pids (our own children): SIGTERM, up to 5 s, then SIGKILL; reaps them.
stop_pids() {
  local p live=() left i
  for p in "$@"; do alive "$p" && live+=("$p"); done
  [ ${#live[@]} -gt 0 ] || return 0
  kill -TERM "${live[@]}" 2>/dev/null
  for ((i = 0; i < 50; i++)); do
    left=()
    for p in "${live[@]}"; do alive "$p" && left+=("$p"); done
    [ ${#left[@]} -gt 0 ] || break
    sleep 0.1
  done
  left=()
  for p in "${live[@]}"; do alive "$p" && left+=("$p"); done
  if [ ${#left[@]} -gt 0 ]; then
    say "warning: ${#left[@]} process(es) ignored SIGTERM for 5 s; sending SIGKILL to ${left[*]}"
    kill -KILL "${left[@]}" 2>/dev/null
  fi
}

# ------------------------------------------------------------------------------------------------
# Hosts: a command runs on host "" (here), in a network namespace, or through ssh. An ssh host runs it
# from the same paths (build, configuration) in a new session whose id, the process group, is written
# into the host's remote folder; stopping kills those groups there (the local ssh client's end alone
# would leave them running). Its stdout and stderr come back through ssh into the run folder.

ssh_opts=(-o BatchMode=yes -o ConnectTimeout=10)
remote_dir="/tmp/shapeform-$(basename "$run")"
# Starts NAME's CMD... on HOST in the background, stdout in $run/NAME.out, stderr in $run/NAME.log;
# its local pid in started_pid (the background subshell execs: the pid is the process itself, or the
# ssh client).
start_on() {
  local host=$1 proc=$2
  shift 2
  case "${host:+${host_kind[$host]}}" in
    "" | local) exec "$@" ;;
    netns) exec ip netns exec "${host_target[$host]}" "$@" ;;
    ssh) exec ssh -n "${ssh_opts[@]}" -- "${host_target[$host]}" "$(printf 'cd %q && mkdir -p %q && exec setsid -w sh -c %q %q' \
           "$root" "$remote_dir" 'echo $$ >"$0" && exec "$@"' "$remote_dir/$proc.pid")$(printf ' %q' "$@")" ;;
  esac </dev/null >"$run/$proc.out" 2>"$run/$proc.log" &
  started_pid=$!
}
# Stops on ssh host $1 the process groups it started there (all, or only process $2's): SIGTERM, up
# to 5 s, then SIGKILL.
remote_stop() {
  ssh "${ssh_opts[@]}" -- "${host_target[$1]}" sh -s -- "$(printf '%q' "$remote_dir")" "${2-}" <<'EOF' >&2
cd "$1" 2>/dev/null || exit 0
if [ -n "$2" ]; then files="$2.pid"; else files=$(ls ./*.pid 2>/dev/null); fi
groups=""
for f in $files; do [ -f "$f" ] && groups="$groups $(cat "$f")"; done
for g in $groups; do kill -s TERM -- "-$g" 2>/dev/null; done
i=0
while [ $i -lt 50 ]; do
  left=""
  for g in $groups; do kill -s 0 -- "-$g" 2>/dev/null && left="$left $g"; done
  [ -n "$left" ] || exit 0
  sleep 0.1
  i=$((i + 1))
done
echo "$(hostname): process groups$left ignored SIGTERM for 5 s: SIGKILL" >&2
for g in $left; do kill -s KILL -- "-$g" 2>/dev/null; done
EOF
}
ssh_hosts() { for h in "${hosts[@]+"${hosts[@]}"}"; do on_ssh "$h" && echo "$h"; done; }
# Waits up to 5 s for the given pids to end by themselves (ssh clients whose remote command was stopped).
settle() {
  local p i any
  for ((i = 0; i < 50; i++)); do
    any=0
    for p in "$@"; do alive "$p" && any=1; done
    [ $any -eq 0 ] && return 0
    sleep 0.1
  done
}

cleanup() {
  local rc=$? i p st bad=0 new_shm h
  trap - INT TERM EXIT
  [ -n "$interrupted" ] && rc=$interrupted
  # The supervisor first, so its recording and summary see the swarm to the end; then the agents.
  if [ -n "$sup_pid" ] && on_ssh "$sup_host"; then remote_stop "$sup_host" supervisor && settle "$sup_pid"; fi
  [ -n "$sup_pid" ] && stop_pids "$sup_pid"
  [ -n "$view_pid" ] && stop_pids "$view_pid" && wait "$view_pid" 2>/dev/null
  for h in $(ssh_hosts); do remote_stop "$h"; done # every group started there (and one started as we stopped)
  settle "${ssh_agent_pids[@]+"${ssh_agent_pids[@]}"}"
  stop_pids "${agent_pids[@]+"${agent_pids[@]}"}"
  for i in "${!agent_pids[@]}"; do
    wait "${agent_pids[$i]}" 2>/dev/null
    st=$?
    if [ $st -ne 0 ]; then
      bad=$((bad + 1))
      [ $bad -le 5 ] && say "agent $i exited with status $st (see $run/agent_$i.log)"
    fi
  done
  [ $bad -gt 5 ] && say "... $bad agents exited abnormally in all"
  # The robots last: their agents, leaving, commanded them zero (a killed agent's robot stops by its
  # watchdog), and their poses are recorded to the end.
  settle "${ssh_vehicle_pids[@]+"${ssh_vehicle_pids[@]}"}"
  stop_pids "${vehicle_pids[@]+"${vehicle_pids[@]}"}"
  for i in "${!vehicle_pids[@]}"; do
    wait "${vehicle_pids[$i]}" 2>/dev/null
    st=$?
    [ $st -eq 0 ] || say "${vehicle_procs[$i]} exited with status $st (see $run/${vehicle_procs[$i]}.log)"
  done
  # The progress tails end by themselves once the supervisor is gone (they flush what is left).
  for ((i = 0; i < 30; i++)); do
    local any=0
    for p in "${tail_pids[@]+"${tail_pids[@]}"}"; do alive "$p" && any=1; done
    [ $any -eq 0 ] && break
    sleep 0.1
  done
  stop_pids "${tail_pids[@]+"${tail_pids[@]}"}"
  wait 2>/dev/null
  # A supervisor on an ssh host recorded there: its recording comes here; then the remote folders go.
  if [ -n "$sup_pid" ] && on_ssh "$sup_host"; then
    mkdir -p "$record" && ssh -n "${ssh_opts[@]}" -- "${host_target[$sup_host]}" \
      "$(printf 'cd %q && tar -cf - .' "$remote_dir/record")" | tar -xf - -C "$record" ||
      say "warning: could not copy the recording from $sup_host ($remote_dir/record)"
  fi
  [ -n "$fleet" ] && [ ${#vehicle_pids[@]} -gt 0 ] && merge_vehicle_records
  for h in $(ssh_hosts); do
    ssh -n "${ssh_opts[@]}" -- "${host_target[$h]}" "$(printf 'rm -rf %q' "$remote_dir")" ||
      say "warning: could not remove $remote_dir on $h"
  done
  if [ -n "$lab_made" ]; then
    "$root/scripts/netlab.sh" down "${lab[0]}" || { say "warning: scripts/netlab.sh down ${lab[0]} failed"; rc=1; }
  fi
  if [ -n "$sup_pid" ]; then
    [ $json -eq 1 ] && grep -E '"event": ?"summary"' "$run/supervisor.out" | tail -n 1
    [ -d "$record" ] && say "recording: $record (metrics, positions, commands, centre$(
      [ ${#vehicle_pids[@]} -gt 0 ] && echo ", the robots' poses in vehicles.csv"): docs/RECORDING.md)"
    [ -n "$view_pid" ] && say "replay: $bin/shapeform_view --replay $run"
    say "logs: $run (supervisor.log, supervisor.out, agent_0..$((n - 1)).log and .out$(
      [ ${#vehicle_pids[@]} -gt 0 ] && echo ", vehicle${fleet:+_<host>}.log and .out"), script.txt)"
  fi
  new_shm=$(comm -13 <(printf '%s\n' "$shm_before") <(shm_list) | sed '/^$/d')
  if [ -n "$new_shm" ]; then
    say "warning: Fast DDS shared-memory files appeared in /dev/shm during the run (not removed:" \
      "another Fast DDS program may own them): $(echo $new_shm)"
  fi
  [ -n "$sup_pid" ] && say "exit status $rc"
  exit "$rc"
}
# --fleet --vehicles: each host's vehicle process recorded into RECORD/vehicle_<host>/ (an ssh host's
# there, copied back here); their rows are merged into RECORD/vehicles.csv in the order of t_s, and the
# folders removed.
merge_vehicle_records() {
  local i proc h files=()
  for i in "${!vehicle_procs[@]}"; do
    proc=${vehicle_procs[$i]} h=${vehicle_hosts[$i]}
    if on_ssh "$h"; then
      mkdir -p "$record/$proc" && ssh -n "${ssh_opts[@]}" -- "${host_target[$h]}" \
        "$(printf 'cd %q && tar -cf - .' "$remote_dir/$proc")" | tar -xf - -C "$record/$proc" ||
        say "warning: could not copy the robots' poses from $h ($remote_dir/$proc)"
    fi
    [ -f "$record/$proc/vehicles.csv" ] && files+=("$record/$proc/vehicles.csv")
  done
  [ ${#files[@]} -gt 0 ] || { say "warning: no vehicles.csv from the vehicle processes"; return 0; }
  # A row cut short by a kill (not 11 fields) is left out: merged, it would no longer be the last line.
  { head -n 1 "${files[0]}"; awk -F, 'FNR > 1 && NF == 11' "${files[@]}" | sort -s -t, -k1,1g; } >"$record/vehicles.csv" &&
    for i in "${!vehicle_procs[@]}"; do rm -rf -- "${record:?}/${vehicle_procs[$i]}"; done
}
on_signal() {
  interrupted=$1
  say "interrupted: stopping the supervisor, $n agents$([ ${#vehicle_pids[@]} -gt 0 ] && echo " and the robots")"
  exit "$1"
}
trap cleanup EXIT
trap 'on_signal 130' INT
trap 'on_signal 143' TERM

# ------------------------------------------------------------------------------------------------
# Launch

say "run folder $run"
if [ $json -eq 1 ]; then
  json_str() { local s=${1//\\/\\\\}; printf '"%s"' "${s//\"/\\\"}"; }
  printf '{"event":"run","dir":%s,"domain":%d,"agents":%d%s%s}\n' "$(json_str "$run")" "$domain" "$n" \
    "${fleet:+,\"fleet\":$(json_str "$fleet_name")}" "${vehicles:+,\"vehicles\":\"$vehicles\"}"
fi
say "scenario $name ($config), $n agents, domain $domain ($domain_note), rate ${rate_eff} Hz," \
  "$([ -n "$init" ] && echo "starts from $init" || echo "seed $seed")," \
  "$([ -n "$steps" ] && echo "$steps iterations" || echo "until converged")$([ -n "$vehicles" ] && echo ", simulated robots")$(
    [ $secure -eq 1 ] && echo ", DDS Security with keystore $keystore")"

# --vehicles: the user's timing is kept; one law step per agent tick is what the robots follow best (each
# agent says so in its log; said here once, where the user looks).
if [ -n "$vehicles" ]; then
  spm=$(yaml_key vehicle seconds_per_model_time)
  awk -v s="${spm:-1}" -v dt="$dt" -v r="$rate_eff" 'BEGIN { d = s * dt - 1 / r; exit !(d > 0.01 / r || d < -0.01 / r) }' &&
    say "note: a law step lasts integration.dt x vehicle.seconds_per_model_time = $(awk -v s="${spm:-1}" -v dt="$dt" \
      'BEGIN { printf "%g", s * dt }') s but an agent tick $(awk -v r="$rate_eff" 'BEGIN { printf "%g", 1 / r }') s" \
      "(1 / agent.rate_hz): for one step per tick --set vehicle.seconds_per_model_time=$(awk -v r="$rate_eff" -v dt="$dt" \
      'BEGIN { printf "%g", 1 / (r * dt) }') (docs/VEHICLES.md)"
fi
if [ -n "$fleet" ]; then
  for h in "${hosts[@]}"; do
    ids=()
    for i in "${!agent_host[@]}"; do [ "${agent_host[$i]}" = "$h" ] && ids+=("$i"); done
    say "fleet $fleet_name: $h ${host_addr[$h]} (${host_kind[$h]} ${host_target[$h]}):" \
      "$([ ${#ids[@]} -gt 0 ] && echo "agents ${ids[*]}" || echo "no agent")$([ "$sup_host" = "$h" ] && echo ", the supervisor")"
  done
  if [ ${#lab[@]} -gt 0 ]; then
    lab_made=1 # before `up`: an interrupted or failed `up` is removed as well (down removes what up recorded)
    "$root/scripts/netlab.sh" up "${lab[0]}" "${lab[1]}" --subnet "${lab[2]}" || exit 1
  fi
fi

supscript="$run/script.txt" suprecord="$record"
if on_ssh "$sup_host"; then # the script goes there; the recording comes back on exit
  supscript="$remote_dir/script.txt" suprecord="$remote_dir/record"
  ssh "${ssh_opts[@]}" -- "${host_target[$sup_host]}" "$(printf 'mkdir -p %q && cat >%q' "$remote_dir" "$supscript")" \
    <"$run/script.txt" || { say "cannot copy the script to $sup_host (${host_target[$sup_host]})"; exit 1; }
fi
host_sets "$sup_host"
supargs=(--config "$config" --domain "$domain" --script "$supscript" --record "$suprecord" "${setargs[@]}"
  "${hsets[@]+"${hsets[@]}"}")
[ $json -eq 1 ] && supargs+=(--json)
start_on "$sup_host" supervisor "$bin/shapeform_supervisor" "${supargs[@]}"
sup_pid=$started_pid
# Progress on the terminal: the supervisor's stderr (and, in text mode, its answers and summary).
tail -q -n +1 -s 0.2 -F --pid="$sup_pid" "$run/supervisor.log" >&2 2>/dev/null &
tail_pids+=($!)
if [ $json -eq 0 ]; then
  tail -q -n +1 -s 0.2 -F --pid="$sup_pid" "$run/supervisor.out" 2>/dev/null &
  tail_pids+=($!)
fi

# The browser view (--view): after the supervisor, on the same domain and config; its URL printed.
if [ $view -eq 1 ]; then
  [ -x "$bin/shapeform_view" ] || die "--view: $bin/shapeform_view not found (run ./scripts/build.sh first)"
  "$bin/shapeform_view" --config "$config" --domain "$domain" "${setargs[@]}" --port 0 --json \
    </dev/null >"$run/view.out" 2>"$run/view.log" &
  view_pid=$!
  url="" i=0
  while [ -z "$url" ] && [ $i -lt 100 ] && alive "$view_pid"; do
    url=$(grep -o '"url":"[^"]*"' "$run/view.out" 2>/dev/null | head -1 | cut -d'"' -f4)
    [ -n "$url" ] || sleep 0.1
    i=$((i + 1))
  done
  [ -n "$url" ] || die "--view: shapeform_view printed no URL (see $run/view.log)"
  say "view: $url"
  [ $json -eq 1 ] && printf '{"event":"view","url":"%s"}\n' "$url"
fi

# The simulated robots (--vehicles sim): before the agents, so that their poses are there when the agents
# start (an agent waits for its first pose anyway). One process per host that runs agents, hosting the
# robots of that host's agents, recording their poses.
if [ -n "$vehicles" ]; then
  vhosts=("")
  [ -n "$fleet" ] && vhosts=("${hosts[@]}")
  for h in "${vhosts[@]}"; do
    ids=()
    for ((i = 0; i < n; i++)); do [ "${agent_host[$i]-}" = "$h" ] && ids+=("$i"); done
    [ ${#ids[@]} -gt 0 ] || continue
    proc=vehicle${h:+_$h} vrecord=$record
    if [ -n "$fleet" ]; then # merged into RECORD/vehicles.csv on exit (merge_vehicle_records)
      vrecord="$record/$proc"
      on_ssh "$h" && vrecord="$remote_dir/$proc"
    fi
    host_sets "$h"
    start_on "$h" "$proc" "$bin/shapeform_vehicle" --ids "$(IFS=,; echo "${ids[*]}")" --config "$config" \
      --domain "$domain" --seed "$seed" --record "$vrecord" "${setargs[@]}" "${hsets[@]+"${hsets[@]}"}" --json
    vehicle_pids+=("$started_pid") vehicle_procs+=("$proc") vehicle_hosts+=("$h")
    on_ssh "$h" && ssh_vehicle_pids+=("$started_pid")
    say "started $proc (pid $started_pid${h:+ on $h}): the robots of agents $([ -n "$fleet" ] && echo "${ids[*]}" || echo "0..$((n - 1))")"
  done
  # Each says "start" once its arguments and config are read (it runs with the agents' config: no
  # surprise here, but a process that did not start is said now, not as agents without poses).
  for i in "${!vehicle_pids[@]}"; do
    k=0
    until grep -q '"event":"start"' "$run/${vehicle_procs[$i]}.out" 2>/dev/null; do
      if ! alive "${vehicle_pids[$i]}" || [ $k -ge 200 ]; then
        say "${vehicle_procs[$i]}: shapeform_vehicle did not start (see $run/${vehicle_procs[$i]}.log)"
        exit 1
      fi
      sleep 0.1
      k=$((k + 1))
    done
  done
fi

for ((i = 0; i < n; i++)); do
  if [ -n "$init" ]; then
    startarg=(--start "${starts[$i]}")
  else
    startarg=(--seed "$seed")
  fi
  host_sets "${agent_host[$i]-}"
  start_on "${agent_host[$i]-}" "agent_$i" "$bin/shapeform_agent" --id "$i" --config "$config" --domain "$domain" \
    "${startarg[@]}" "${setargs[@]}" "${hsets[@]+"${hsets[@]}"}" --json
  agent_pids+=("$started_pid")
  on_ssh "${agent_host[$i]-}" && ssh_agent_pids+=("$started_pid")
  sleep "$agent_interval" # a stagger avoids a discovery storm
done
say "started $n agents (pids ${agent_pids[0]}..${agent_pids[$((n - 1))]}) and the supervisor (pid $sup_pid)"

wait "$sup_pid"
exit $?
