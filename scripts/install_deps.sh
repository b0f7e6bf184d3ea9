#!/usr/bin/env bash
# Installs every Debian 12 package shapeform needs to build, test, benchmark and plot, then the tests'
# validators from the npm registry (tests/npm/package.json: readers written by others, exact versions
# pinned by tests/npm/package-lock.json) into build/npm, never globally. The product never needs them.
#
#   scripts/install_deps.sh
#
# Idempotent: packages already present are skipped, and the npm folder is only reinstalled when the
# lock file changed. Run as root.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools
  libeigen3-dev libyaml-cpp-dev catch2 libcli11-dev nlohmann-json3-dev libmuparser-dev libedit-dev
  libcpp-httplib-dev libssl-dev openssl faketime
  python3 python3-matplotlib python3-numpy python3-pil python3-yaml
  iproute2 iptables tcpdump procps psmisc
  chromium chromium-driver python3-selenium
  libzstd-dev liblz4-dev libwebsocketpp-dev libasio-dev
)
# Node.js and npm for the test validators: the machine's own when it has them, else Debian's.
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
else
  if [ "$(id -u)" -ne 0 ]; then
    echo "install_deps: missing packages (${missing[*]}); run as root" >&2
    exit 1
  fi
  echo "install_deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The tests' npm validators: `npm ci` from the committed lock into build/npm (no install scripts run).
npm_dir=build/npm
if ! cmp -s tests/npm/package-lock.json "$npm_dir/package-lock.json" || [ ! -d "$npm_dir/node_modules" ]; then
  echo "install_deps: installing the tests' npm validators into $npm_dir"
  rm -rf "$npm_dir"
  mkdir -p "$npm_dir"
  cp tests/npm/package.json tests/npm/package-lock.json "$npm_dir/"
  if ! (cd "$npm_dir" && npm ci --no-audit --no-fund --ignore-scripts --loglevel=error); then
    rm -rf "$npm_dir"
    echo "install_deps: npm ci failed in $npm_dir (is the npm registry reachable?)" >&2
    exit 1
  fi
else
  echo "install_deps: the tests' npm validators are in $npm_dir"
fi
