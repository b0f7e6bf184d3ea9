#!/usr/bin/env bash
# Runs every test: installs dependencies, configures (warnings as errors), builds, runs ctest.
#
#   scripts/test.sh [CTEST_ARGS...]
#
# The whole ctest run is wrapped in scripts/check_loopback.sh: any RTPS packet of the project seen on a
# non-loopback interface fails the run. The exit status is the tests'. Extra arguments go to ctest.
case "${1-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;; esac
set -uo pipefail
cd "$(dirname "$0")/.."
./scripts/build.sh -DSHAPEFORM_WERROR=ON || exit 1
exec ./scripts/check_loopback.sh ctest --test-dir build --output-on-failure --timeout 900 -j2 "$@"
