#!/usr/bin/env bash
# Makes (or extends) a DDS Security keystore for a swarm, with openssl only.
#
#   scripts/make_keystore.sh DIR [--agents N] [--days D] [--enclave NAME ...]
#
# Layout (the one ROS 2's sros2 keystores use, so robotics users recognise it):
#   DIR/public/identity_ca.cert.pem     the identity authority: issues one certificate per participant
#   DIR/public/permissions_ca.cert.pem  the permissions authority: signs the governance and the
#                                       permissions documents, and nothing else
#   DIR/private/*_ca.key.pem            their keys (mode 600): keep them off the swarm's hosts
#   DIR/enclaves/governance.xml|.p7s    the domain rules: unauthenticated participants refused, join
#                                       access control on, discovery, liveliness and data encrypted,
#                                       every RTPS message signed
#   DIR/enclaves/NAME/                  one identity: cert.pem, key.pem (mode 600), governance.p7s,
#                                       permissions.xml, permissions.p7s, identity_ca.cert.pem,
#                                       permissions_ca.cert.pem (copies: an enclave folder is
#                                       self-contained, copy it alone to the host that uses it)
# Both authorities use ECDSA prime256v1. They are two, not one: Fast DDS 2.9.1 as Debian ships it
# accepts a permissions document signed by any certificate the permissions authority issued
# (CVE-2023-24010), so with one authority any agent could sign itself the right to command. Here
# the permissions authority issues no certificate at all (docs/SECURITY.md).
# Enclaves made: `supervisor` and `viewer` (read-only monitors: shapeform_view, shapeform_echo,
# shapeform_topics, the benchmark probe), or instead only the ones named with --enclave (supervisor,
# viewer, vehicle: a robot driver such as shapeform_vehicle, or agent_K); and `agent_0` .. `agent_{N-1}` (a group process uses the enclave of its first
# agent id).
# Permissions (the policy): each topic's row of the topic table (common/dds/topic_table.hpp) names the
# roles that may publish and subscribe to it; rules() below is generated from it, and docs/SECURITY.md
# shows it as a table. agent_K enclaves are of the role agent; supervisor and viewer of their own.
# Certificates and grants are valid for D days from now (default 365; the authorities for
# max(D, 3650)). Running it again on an existing keystore keeps its authorities and enclaves and adds
# the missing ones (`--agents 20` on a keystore of 12 agents adds agent_12 .. agent_19).
# Exit status: 0 ok, 1 openssl failed, 2 bad usage.
case "${1-}" in -h|--help|"") awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; [ -n "${1-}" ]; exit $? ;; esac
set -euo pipefail

readonly prog=make_keystore
die() { echo "$prog: $*" >&2; exit 2; }

dir=$1
shift
agents=0
days=365
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --agents) [[ ${2-} =~ ^[0-9]+$ ]] && [ "${2}" -le 1000 ] || die "--agents: expected 0..1000, got '${2-}'"
      agents=$2; shift 2 ;;
    --days) [[ ${2-} =~ ^[0-9]+$ ]] && [ "${2}" -ge 1 ] && [ "${2}" -le 36500 ] || die "--days: expected 1..36500, got '${2-}'"
      days=$2; shift 2 ;;
    --enclave) [[ ${2-} =~ ^(supervisor|viewer|vehicle|agent_[0-9]+)$ ]] || die "--enclave: expected supervisor, viewer, vehicle or agent_K, got '${2-}'"
      extra+=("$2"); shift 2 ;;
    *) die "unknown argument '${1:0:40}' (see --help)" ;;
  esac
done
command -v openssl >/dev/null || { echo "$prog: openssl not found: run scripts/install_deps.sh" >&2; exit 1; }
[ -e "$dir" ] && [ ! -d "$dir" ] && die "DIR: '$dir' exists and is not a folder"

umask 077
mkdir -p "$dir/public" "$dir/private" "$dir/enclaves"
ca_days=$((days > 3650 ? days : 3650))
# Dates of the grants: the certificates' validity, in the permissions' xs:dateTime form.
not_before=$(date -u +%Y-%m-%dT%H:%M:%S)
not_after=$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)

ossl() { openssl "$@" 2>"$dir/.openssl.err" || { echo "$prog: openssl $1 failed:" >&2; cat "$dir/.openssl.err" >&2; exit 1; }; }

for ca in identity_ca permissions_ca; do
  if [ ! -f "$dir/private/$ca.key.pem" ]; then
    ossl ecparam -name prime256v1 -genkey -noout -out "$dir/private/$ca.key.pem"
    ossl req -x509 -new -key "$dir/private/$ca.key.pem" -out "$dir/public/$ca.cert.pem" -days "$ca_days" -sha256 \
      -subj "/CN=shapeform ${ca/_ca/} authority"
    echo "$prog: new ${ca/_ca/} authority in $dir"
  fi
  [ -f "$dir/public/$ca.cert.pem" ] || die "DIR: '$dir/private/$ca.key.pem' exists but '$dir/public/$ca.cert.pem' does not: not a keystore of this script"
done
id_cert=$dir/public/identity_ca.cert.pem id_key=$dir/private/identity_ca.key.pem
perm_cert=$dir/public/permissions_ca.cert.pem perm_key=$dir/private/permissions_ca.key.pem

sign() { # IN OUT: S/MIME signature by the permissions authority, the form Fast DDS reads
  ossl smime -sign -in "$1" -text -out "$2" -signer "$perm_cert" -inkey "$perm_key"
}

governance=$dir/enclaves/governance.xml
if [ ! -f "$dir/enclaves/governance.p7s" ]; then
  cat >"$governance" <<'EOF'
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>232</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
  sign "$governance" "$dir/enclaves/governance.p7s"
fi

# The permissions of each role, generated from the topic table (common/dds/topic_table.hpp) by
# scripts/gen_topic_docs.sh; a ctest fails while this block differs from the table.
# BEGIN GENERATED topics: permissions
rules() { # NAME -> the allow rules of its role
  case "$1" in
    agent_*)
      echo '<publish><topics><topic>shapeform/state</topic><topic>shapeform/state_batch</topic><topic>shapeform/status</topic><topic>rt/*/cmd_vel</topic><topic>shapeform/status_batch</topic></topics></publish>'
      echo '<subscribe><topics><topic>shapeform/state</topic><topic>shapeform/state_batch</topic><topic>shapeform/command</topic><topic>shapeform/target</topic><topic>rt/*/odom</topic><topic>rt/*/pose</topic></topics></subscribe>'
      ;;
    supervisor)
      echo '<publish><topics><topic>shapeform/command</topic><topic>shapeform/target</topic><topic>shapeform/metrics</topic><topic>rt/shapeform/agents</topic><topic>rt/shapeform/markers</topic></topics></publish>'
      echo '<subscribe><topics><topic>shapeform/state</topic><topic>shapeform/state_batch</topic><topic>shapeform/command</topic><topic>shapeform/status</topic><topic>shapeform/status_batch</topic></topics></subscribe>'
      ;;
    viewer)
      echo '<subscribe><topics><topic>shapeform/state</topic><topic>shapeform/state_batch</topic><topic>shapeform/command</topic><topic>shapeform/target</topic><topic>shapeform/metrics</topic><topic>shapeform/status</topic><topic>rt/*/cmd_vel</topic><topic>rt/*/odom</topic><topic>rt/*/pose</topic><topic>rt/shapeform/agents</topic><topic>rt/shapeform/markers</topic><topic>shapeform/status_batch</topic></topics></subscribe>'
      ;;
    vehicle)
      echo '<publish><topics><topic>rt/*/odom</topic><topic>rt/*/pose</topic></topics></publish>'
      echo '<subscribe><topics><topic>rt/*/cmd_vel</topic></topics></subscribe>'
      ;;
  esac
}
# END GENERATED

make_enclave() { # NAME
  local name=$1 e=$dir/enclaves/$1
  [ -f "$e/permissions.p7s" ] && return 0
  mkdir -p "$e"
  ossl ecparam -name prime256v1 -genkey -noout -out "$e/key.pem"
  ossl req -new -key "$e/key.pem" -out "$e/req.csr" -subj "/CN=$name"
  ossl x509 -req -in "$e/req.csr" -CA "$id_cert" -CAkey "$id_key" -set_serial "0x$(openssl rand -hex 16)" \
    -out "$e/cert.pem" -days "$days" -sha256
  rm -f "$e/req.csr"
  cat >"$e/permissions.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>CN=$name</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>232</max></id_range></domains>
        $(rules "$name" | paste -sd ' ')
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
  sign "$e/permissions.xml" "$e/permissions.p7s"
  cp "$id_cert" "$e/identity_ca.cert.pem"
  cp "$perm_cert" "$e/permissions_ca.cert.pem"
  cp "$dir/enclaves/governance.p7s" "$e/governance.p7s"
  chmod 644 "$e"/*.pem "$e"/*.p7s "$e"/*.xml
  chmod 600 "$e/key.pem"
  chmod 755 "$e"
}

if [ ${#extra[@]} -gt 0 ]; then names=("${extra[@]}"); else names=(supervisor viewer); fi
for ((i = 0; i < agents; i++)); do names+=("agent_$i"); done
made=0
for name in "${names[@]}"; do
  [ -f "$dir/enclaves/$name/permissions.p7s" ] || made=$((made + 1))
  make_enclave "$name"
done
rm -f "$dir/.openssl.err"
chmod 755 "$dir" "$dir/public" "$dir/enclaves"
chmod 644 "$id_cert" "$perm_cert" "$governance" "$dir/enclaves/governance.p7s"
echo "$prog: $dir: $made new enclave(s), $(ls -d "$dir"/enclaves/*/ | wc -l) in all, valid until $not_after UTC for the new ones"
