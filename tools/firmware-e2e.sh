#!/usr/bin/env bash
# The end-to-end tests of tests/e2e.rs against the firmware's own tasks running on Linux
# (the firmware's host build: embassy's std executor, embassy-net over a TAP device, the
# simulated CAN bus of simulated Whistles).
#
#   tools/firmware-e2e.sh            (as root: it creates a network namespace and a TAP device)
#
# Builds the firmware for the host and the e2e test binary, then, inside a new network
# namespace (`unshare -n`: no traffic leaves it), creates tap0 with the address 192.168.1.1/24
# (the firmware's default ARMGATE_IP is 192.168.1.50/24) and runs the tests one at a time with
# ARMGATE_E2E_FIRMWARE set: each test starts the firmware on tap0 and talks to it over UDP.
# Without the privileges it says why and exits 0 — except under CI=true, where that is a failure.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! unshare -n true 2>/dev/null || ! unshare -n ip tuntap add dev probe0 mode tap 2>/dev/null; then
    why="cannot create a network namespace with a TAP device (needs root, or CAP_SYS_ADMIN and CAP_NET_ADMIN, /dev/net/tun, and iproute2)"
    if [[ "${CI:-}" == "true" ]]; then
        echo "firmware-e2e: $why" >&2
        exit 1
    fi
    echo "firmware-e2e: skipped: $why" >&2
    exit 0
fi

cargo build -p armgate-firmware
firmware=${CARGO_TARGET_DIR:-target}/debug/armgate-firmware
tests=$(cargo test -p armgate-sim --test e2e --no-run --message-format=json-render-diagnostics |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -n 1)
if [[ -z "$tests" || ! -x "$tests" ]]; then
    echo "firmware-e2e: cannot find the e2e test executable after the build" >&2
    exit 1
fi

export ARMGATE_E2E_FIRMWARE=$PWD/${firmware#"$PWD"/}
[[ "$firmware" == /* ]] && export ARMGATE_E2E_FIRMWARE=$firmware
unshare -n bash -euo pipefail -c '
    ip link set lo up
    ip tuntap add dev tap0 mode tap
    ip addr add 192.168.1.1/24 dev tap0
    ip link set tap0 up
    exec "$0" --test-threads 1
' "$tests"
