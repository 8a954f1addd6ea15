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
#    client, 192.168.1.2/24 (the firmware's default ARMGATE_IP is 192.168.1.50/24) and runs the
#    tests one at a time with ARMGATE_E2E_FIRMWARE set: each test starts the firmware on tap0 and
#    talks to it over UDP. Three such namespaces take the tests from one queue side by
#    side; the streaming tests run alone after them.
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
# Runs the e2e tests named in file $1 (taken off it one by one, so several namespaces can
# share it) in a new network namespace with its own tap0, one at a time (the firmware's port is
# fixed at build time); its output goes to $2.
run_namespace() {
    unshare -n bash -euo pipefail -c '
        ip link set lo up
        ip tuntap add dev tap0 mode tap
        ip addr add 192.168.1.1/24 dev tap0
        ip addr add 192.168.1.2/24 dev tap0
        ip link set tap0 up
        failed=0
        next() { flock "$1" sh -c "head -n 1 \"\$0\"; sed -i 1d \"\$0\"" "$1"; }
        while name=$(next "$1") && [[ -n $name ]]; do
            "$0" --test-threads 1 --exact "$name" || failed=1
        done
        exit $failed
    ' "$tests" "$1" >"$2" 2>&1
}
# Prints what namespace $1's log $2 says (all of it if it failed, status $3).
report() {
    echo "firmware-e2e: $1 (exit $3):"
    if (( $3 == 0 )); then grep -E '^test .* \.\.\. ' "$2" || true; else cat "$2"; fi
    rm -f "$2"
}

# Three namespaces take the tests from one queue side by side; the streaming tests, whose
# client must send every few control periods, run after them alone (a loaded machine delays
# a debug build's replies).
queue=$(mktemp) streams=$(mktemp)
"$tests" --list --format terse | sed -n 's/: test$//p' >"$queue"
total=$(wc -l <"$queue")
grep -E 'stream|jog' "$queue" >"$streams" || true
sed -i -E '/stream|jog/d' "$queue"
logs=() pids=()
for space in 1 2 3; do
    logs+=("$(mktemp)")
    run_namespace "$queue" "${logs[-1]}" &
    pids+=($!)
done
failed=0
for i in "${!pids[@]}"; do
    status=0
    wait "${pids[$i]}" || status=$?
    report "namespace $((i + 1)) of 3" "${logs[$i]}" "$status"
    (( status == 0 )) || failed=1
done
log=$(mktemp)
status=0
run_namespace "$streams" "$log" || status=$?
report "the streaming tests, alone" "$log" "$status"
(( status == 0 )) || failed=1
rm -f "$queue" "$streams"
if (( failed )); then
    echo "firmware-e2e: end-to-end tests failed against the firmware (above)" >&2
    exit 1
fi
echo "firmware-e2e: $total end-to-end tests passed against the firmware"
