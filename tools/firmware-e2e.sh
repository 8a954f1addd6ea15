#!/usr/bin/env bash
# The firmware's own tasks running on Linux (its host build: embassy's std executor,
# embassy-net over a TAP device, the simulated CAN bus of simulated Whistles), checked against
# armgate-sim:
#
#   tools/firmware-e2e.sh            (as root: it creates a network namespace and a TAP device)
#
# 1. the differential test: tools/replay/session.txt replayed through armgate-sim and through
#    the firmware on a virtual clock, their transcripts compared tick by tick;
# 2. the end-to-end tests of tests/e2e.rs: inside a new network namespace (`unshare -n`: no
#    traffic leaves it) it creates tap0 with the addresses 192.168.1.1/24 and, for a second
#    client, 192.168.1.2/24 (the firmware's default ARMGATE_IP is 192.168.1.50/24) and runs the tests one at a time with ARMGATE_E2E_FIRMWARE
#    set: each test starts the firmware on tap0 and talks to it over UDP.
# Without the privileges for that it says why and exits 0 — except under CI=true, where that is
# a failure.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cargo build -p armgate-firmware
firmware=${CARGO_TARGET_DIR:-target}/debug/armgate-firmware
tests=$(cargo test -p armgate-sim --test e2e --no-run --message-format=json-render-diagnostics |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | grep "/deps/e2e-" | tail -n 1)
if [[ -z "$tests" || ! -x "$tests" ]]; then
    echo "firmware-e2e: cannot find the e2e test executable after the build" >&2
    exit 1
fi

# The differential test (no privileges needed): one recorded exchange replayed through both
# shells on a virtual clock must give the same transcript, tick by tick — replies, notices, the
# drive manager's state and joints, the frames and bits on the bus, the simulated drives.
cargo build -p armgate-sim
sim=${CARGO_TARGET_DIR:-target}/debug/armgate-sim
recording=tools/replay/session.txt
ticks=200
expected=$(mktemp) actual=$(mktemp)
trap 'rm -f "$expected" "$actual"' EXIT
"$sim" --replay "$recording" "$ticks" >"$expected"
ARMGATE_REPLAY="$recording $ticks" "$firmware" >"$actual"
if ! diff -u "$expected" "$actual" >&2; then
    echo "firmware-e2e: the firmware's transcript differs from armgate-sim's (above)" >&2
    exit 1
fi
echo "firmware-e2e: differential test: $ticks ticks, $(grep -c reply "$expected") with replies, identical transcripts"

if ! unshare -n true 2>/dev/null || ! unshare -n ip tuntap add dev probe0 mode tap 2>/dev/null; then
    why="cannot create a network namespace with a TAP device (needs root, or CAP_SYS_ADMIN and CAP_NET_ADMIN, /dev/net/tun, and iproute2)"
    if [[ "${CI:-}" == "true" ]]; then
        echo "firmware-e2e: $why" >&2
        exit 1
    fi
    echo "firmware-e2e: skipped: $why" >&2
    exit 0
fi

ARMGATE_E2E_FIRMWARE=$(realpath "$firmware")
export ARMGATE_E2E_FIRMWARE
unshare -n bash -euo pipefail -c '
    ip link set lo up
    ip tuntap add dev tap0 mode tap
    ip addr add 192.168.1.1/24 dev tap0
    ip addr add 192.168.1.2/24 dev tap0
    ip link set tap0 up
    exec "$0" --test-threads 1
' "$tests"
