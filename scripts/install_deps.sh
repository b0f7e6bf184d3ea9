#!/usr/bin/env bash
# Installs every Debian 12 package shapeform needs to build, test, benchmark and plot.
#
#   scripts/install_deps.sh
#
# Idempotent: packages already present are skipped by apt-get. Run as root.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  libeigen3-dev libyaml-cpp-dev catch2 libcli11-dev nlohmann-json3-dev libmuparser-dev libedit-dev
  libcpp-httplib-dev libssl-dev openssl faketime
  python3 python3-matplotlib python3-numpy python3-pil python3-yaml
  iproute2 iptables tcpdump procps psmisc
  chromium chromium-driver python3-selenium
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install_deps: missing packages (${missing[*]}); run as root" >&2
  exit 1
fi
echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
