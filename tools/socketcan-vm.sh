#!/usr/bin/env bash
# armgate over a real Linux CAN stack, in a VM (issue 36; docs/drives.md, "SocketCAN in a VM"):
#
#   tools/socketcan-vm.sh            (as root: it installs Debian packages and a PyPI venv)
#
# The host's kernel may have no SocketCAN at all; Debian's own kernel has. This boots it with
# virtme-ng over the host's file system (QEMU's TCG, no KVM needed) with two emulated Kvaser PCI
# controllers (kernel driver kvaser_pci, sja1000) on one emulated CAN bus, can0 and can1, and in
# the VM:
#   1. shows the kernel and each interface's driver, and runs the README's `ip link` recipe
#      ("SocketCAN setup") verbatim, bit rate read back;
#   2. ENOBUFS: armgate-sim on can0 at the default txqueuelen of 10, the Whistle simulator
#      (`armgate-sim --whistles`) on can1: frames refused by the full queue are counted and the
#      drives fault, as the README says;
#      then the README's desk setup on vcan0 (`ON`, then `emcy 103` on the simulator's stdin);
#   3. the recipe in full (txqueuelen 1000) and five end-to-end tests (tests/e2e.rs with
#      ARMGATE_E2E_CAN=can0,can1: each test starts armgate-sim on can0 and the Whistle
#      simulator on can1), can0 captured with dumpcap meanwhile; the tests must pass, among them
#      a drive's emergency (ER32) and the Whistle simulator killed mid-move (ER30);
#   4. the firmware's own tasks (its Linux build, tools/firmware-e2e.sh's TAP addresses, its
#      FDCAN seam as can0: ARMGATE_CAN=socketcan:can0) in `a_full_session_over_udp` against the
#      Whistle simulator on can1; it must pass;
#   5. `ip -s -d link` of both interfaces (frames counted by the kernel) and the receive overruns
#      of the emulated controllers.
# Back on the host, the capture is decoded frame by frame by Wireshark's CANopen dissector and by
# tools/wireshark/armgate.lua: every frame must be decoded by both.
# The guest keeps time by the instructions it executes, on one vCPU (the `vng` call says why).
# What it does not show (docs/drives.md, "SocketCAN in a VM"): QEMU's CAN bus has no bit timing,
# so bus load and latency stay the simulated bus's.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# -- inside the VM -------------------------------------------------------------------------------
if [[ "${1:-}" == "--inside" ]]; then
    out=$2 bin=$3 e2e=$4 e2e_tests=$5
    # Also kept in a file, which the host prints if the guest's console output did not come.
    exec > >(tee "$out/vm.txt") 2>&1
    # The binaries (without debug info), the tests' files and the capture in the guest's memory,
    # not read or written over 9p from the host's file system during the tests: a process
    # waiting for the host leaves the guest idle, and an idle guest's clock jumps ahead (-icount
    # sleep=off, below), which the processes still running would see as a stall.
    mem=$(mktemp -d)
    mount -t tmpfs -o size=600m tmpfs "$mem"
    for file in "$bin/armgate-sim" "$bin/armgate" "$bin/armgate-firmware" "$e2e"; do # stripped on the host
        cp "$out/bin/${file##*/}" "$mem/"
        mount --bind "$mem/${file##*/}" "$file"
    done
    export TMPDIR=$mem/tmp
    mkdir "$TMPDIR"
    sim=$bin/armgate-sim client=$bin/armgate
    robot=robots/ranger-mk1.toml
    echo "kernel: $(uname -r)"
    for iface in can0 can1; do
        driver=$(basename "$(readlink "/sys/class/net/$iface/device/driver")")
        echo "$iface: kernel driver $driver ($(modinfo -F description "$driver" 2>/dev/null || true))"
    done

    # The README's recipe, verbatim but for `sudo` (root here), for can0 and can1.
    recipe=$(awk '/^\*\*SocketCAN setup\.\*\*/ { found = 1 } found && /^```sh$/ { inside = 1; next }
        inside && /^```$/ { exit } inside { print }' README.md)
    [[ -n "$recipe" ]] || { echo "socketcan-vm: no recipe in README.md's SocketCAN setup"; exit 1; }
    echo "the README's recipe:"
    echo "$recipe" | sed 's/^/    /'
    setup() { # IFACE [PATTERN]: the recipe for IFACE, without the lines matching PATTERN
        echo "$recipe" | sed "s/can0/$1/g; s/^sudo //" | grep -v -e "${2:-^$}" | bash -eu
    }
    # A drive-side process (the Whistle simulator) and a controller (armgate-sim) on IFACE.
    whistles_on() { # IFACE LOG [ARGS...]
        "$sim" --whistles --can "socketcan:$1" --robot "$robot" "${@:3}" </dev/null 2>"$out/$2" &
        whistles=$!
        for _ in $(seq 50); do # until it is on the bus
            grep -q "simulated Whistles" "$out/$2" 2>/dev/null && return
            sleep 0.1
        done
    }
    controller_on() { # IFACE LOG [ARGS...]
        "$sim" --can "socketcan:$1" --robot "$robot" --quiet "${@:3}" 2>"$out/$2" &
        controller=$!
        for _ in $(seq 50); do # until it answers
            "$client" --timeout 1s status >/dev/null 2>&1 && return
            sleep 0.2
        done
        echo "socketcan-vm: armgate-sim on $1 never answered"
        exit 1
    }
    stop() { # PID...: SIGTERM (exit summaries are printed), then wait
        kill "$@" 2>/dev/null || true
        wait "$@" 2>/dev/null || true
    }
    drives() { "$client" --timeout 1s status 2>&1 | sed -n 's/^drives *//p'; }

    # 1. ENOBUFS: the recipe without its txqueuelen line on can0 (the kernel's default, 10).
    setup can0 txqueuelen
    setup can1
    ip -d link show can0 | sed -n '1p; /bitrate/p'
    whistles_on can1 enobufs-whistles.txt
    controller_on can0 enobufs-sim.txt
    sleep 1
    state=$(drives)
    stop "$controller"
    stop "$whistles"
    refused=$(sed -n 's/.* \([0-9]*\) frames refused by a full transmit queue.*/\1/p' "$out/enobufs-sim.txt")
    echo "txqueuelen 10: $refused frames refused by a full transmit queue (ENOBUFS); drives: $state"
    grep SocketCAN "$out/enobufs-sim.txt" | sed 's/^/    /'
    # QEMU's CAN bus has no bit timing: the emulated controller may drain the queue as fast as
    # it is filled, so a run need not provoke ENOBUFS. What the README promises is that a
    # refused frame is never a silent loss: where frames were refused, the drives are faulted.
    if [[ "$refused" -gt 0 && "$state" != faulted* ]]; then
        echo "socketcan-vm: frames were refused (ENOBUFS) but the drives are not faulted"
        exit 1
    elif [[ ! "$refused" -gt 0 ]]; then
        echo "txqueuelen 10: ENOBUFS not provoked in this run (QEMU's bus has no bit timing)"
    fi

    # The README's desk setup ("Two processes on a desk"): both processes on one vcan0, a fault
    # typed into the Whistle simulator's standard input (a pipe here).
    ip link add dev vcan0 type vcan && ip link set up vcan0
    mkfifo "$mem/faults"
    "$sim" --whistles --can socketcan:vcan0 --robot "$robot" <"$mem/faults" 2>"$out/desk-whistles.txt" &
    whistles=$!
    exec 3>"$mem/faults"
    for _ in $(seq 50); do # until it is on the bus
        grep -q "simulated Whistles" "$out/desk-whistles.txt" 2>/dev/null && break
        sleep 0.1
    done
    controller_on vcan0 desk-sim.txt
    "$client" --timeout 1s on >/dev/null 2>&1 || true
    for _ in $(seq 20); do
        state=$(drives)
        [[ "$state" != starting* ]] && break
        sleep 0.2
    done
    echo "the desk setup on vcan0, after ON: drives: $state"
    echo "emcy 103" >&3
    for _ in $(seq 20); do
        sleep 0.2
        faulted=$(drives)
        [[ "$faulted" == faulted* ]] && break
    done
    echo "after typing 'emcy 103' into the Whistle simulator: drives: $faulted"
    exec 3>&-
    stop "$controller"
    stop "$whistles"
    if [[ "$state" != running* || "$faulted" != "faulted (ER32"* ]]; then
        sed 's/^/    /' "$out/desk-sim.txt" "$out/desk-whistles.txt"
        echo "socketcan-vm: the README's desk setup on vcan0 did not run, or the fault did not come"
        exit 1
    fi

    # 2. The recipe in full (txqueuelen 1000) and the end-to-end tests over the bus: each test
    # starts armgate-sim on can0 and the Whistle simulator on can1 (ARMGATE_E2E_CAN), one test
    # at a time, can0 captured meanwhile (its first 6000 frames: every kind of frame, decoded
    # quickly).
    setup can0
    ip -d link show can0 | sed -n '1p; /bitrate/p'
    dumpcap -q -i can0 -c 6000 -w "$mem/can0.pcapng" 2>"$out/dumpcap.txt" &
    dumpcap=$!
    for _ in $(seq 50); do # until it captures
        grep -q "Capturing on" "$out/dumpcap.txt" 2>/dev/null && break
        sleep 0.1
    done
    e2e_started=$SECONDS
    e2e_status=0
    # shellcheck disable=SC2086 # the test names, one word each
    ARMGATE_E2E_CAN=can0,can1 "$e2e" --test-threads 1 --exact $e2e_tests >"$mem/e2e.txt" 2>&1 ||
        e2e_status=$?
    stop "$dumpcap"
    cp "$mem/can0.pcapng" "$mem/e2e.txt" "$out/"
    echo "the end-to-end tests over can0/can1, $((SECONDS - e2e_started)) s of the guest's time:"
    grep -E '^test |^test result' "$out/e2e.txt" | sed 's/^/    /' || true
    echo "receive overruns of the emulated controllers: can0 $(cat /sys/class/net/can0/statistics/rx_over_errors), can1 $(cat /sys/class/net/can1/statistics/rx_over_errors)"
    if [[ $e2e_status -ne 0 ]]; then
        # What failed, with the Whistle simulators' exit summaries.
        sed -n '/^failures:$/,$p' "$out/e2e.txt" | sed 's/^/    /'
        echo "socketcan-vm: end-to-end tests failed over SocketCAN in the VM (exit code $e2e_status)"
        exit 1
    fi

    # 3. The firmware's own tasks over can0 (its FDCAN seam as SocketCAN, its Ethernet as a TAP
    # device with tools/firmware-e2e.sh's addresses, in the guest's own network namespace, where
    # the CAN interfaces are), the Whistle simulator on can1: one session, asserted.
    modprobe tun
    ip tuntap add dev tap0 mode tap
    ip addr add 192.168.1.1/24 dev tap0
    ip addr add 192.168.1.2/24 dev tap0
    ip link set tap0 up
    firmware_started=$SECONDS
    firmware_status=0
    ARMGATE_E2E_FIRMWARE=$bin/armgate-firmware ARMGATE_E2E_CAN=can0,can1 "$e2e" --test-threads 1 \
        --exact a_full_session_over_udp >"$mem/e2e-firmware.txt" 2>&1 || firmware_status=$?
    cp "$mem/e2e-firmware.txt" "$out/"
    echo "the firmware's tasks over can0/can1 (ARMGATE_CAN=socketcan:can0), $((SECONDS - firmware_started)) s of the guest's time:"
    grep -E '^test |^test result' "$out/e2e-firmware.txt" | sed 's/^/    /' || true
    if [[ $firmware_status -ne 0 ]]; then
        sed -n '/^failures:$/,$p' "$out/e2e-firmware.txt" | sed 's/^/    /'
        echo "socketcan-vm: the firmware's session failed over SocketCAN in the VM (exit code $firmware_status)"
        exit 1
    fi

    # 4. The kernel's counters, and the frames the emulated controllers lost (receive overruns:
    # with one vCPU the receiving interrupt runs before the next frame is written, see the
    # `vng` call below).
    ip -s -d link show can0
    ip -s -d link show can1
    for iface in can0 can1; do
        echo "$iface: $(cat /sys/class/net/$iface/statistics/rx_packets) frames received, $(cat /sys/class/net/$iface/statistics/tx_packets) sent, $(cat /sys/class/net/$iface/statistics/rx_over_errors) receive overruns"
    done
    touch "$out/passed"
    exit 0
fi

# -- on the host ---------------------------------------------------------------------------------
step_started=$SECONDS
# shellcheck source=tools/apt.sh
source tools/apt.sh
kernel=$(ls /boot/vmlinuz-*-amd64 2>/dev/null | sort -V | tail -n 1 || true)
if [[ -z "$kernel" ]] || ! command -v qemu-system-x86_64 >/dev/null || ! command -v busybox >/dev/null ||
    ! command -v candump >/dev/null || ! command -v dumpcap >/dev/null; then
    echo "socketcan-vm: apt: qemu-system-x86 linux-image-amd64 busybox-static can-utils tshark"
    echo "wireshark-common wireshark-common/install-setuid boolean false" | debconf-set-selections
    apt_install qemu-system-x86 linux-image-amd64 busybox-static can-utils tshark
    kernel=$(ls /boot/vmlinuz-*-amd64 | sort -V | tail -n 1)
fi
target=$(realpath "${CARGO_TARGET_DIR:-target}")
venv=$target/vng-venv
if [[ ! -x "$venv/bin/vng" ]]; then
    echo "socketcan-vm: PyPI: virtme-ng into $venv"
    /usr/bin/python3 -m venv "$venv"
    "$venv/bin/python" -m pip install -q --retries 5 --timeout 60 virtme-ng
fi

# The test executable and the client as `cargo test` builds them (nothing to build in CI).
cargo build -q -p armgate-client
e2e=$(cargo test -q -p armgate-sim --test e2e --no-run --message-format=json-render-diagnostics |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | grep "/deps/e2e-" | tail -n 1)
# armgate-sim itself and the firmware's Linux build with armgate-core optimised, in their usual
# place (target/debug, where the tests start them): the simulated Whistles keep time with the guest's clock, and unoptimised
# they fell behind it under TCG (a loop turn of up to 1.8 s, against 0.1 to 0.3 s optimised);
# optimised, the guest also has fewer instructions to run, which is the step's wall time. Not
# in everyone's dev builds: it triples core's compile time. The next plain `cargo build` puts
# the unoptimised one back without building anything.
cargo build -q --config 'profile.dev.package.armgate-core.opt-level=2' -p armgate-sim -p armgate-firmware
# A small representative set (17 to 26 s of the guest's time, 30 to 85 s of the host's): start-up and a Cartesian session on
# the interpreter schedule, the PDO schedule's session, ST at cruise, a drive's emergency, and
# the Whistle simulator killed mid-move.
e2e_tests="a_full_session_over_udp the_pdo_schedule_runs_a_session
    st_at_cruise_brings_the_arm_to_rest_within_its_acceleration_limits
    socketcan::an_emergency_from_a_drive_on_the_bus_stops_the_arm_and_on_starts_it_again
    socketcan::the_whistles_killed_mid_move_stop_the_arm_as_drives_not_answering"

built=$SECONDS
out=$target/socketcan-vm
rm -rf "$out"
mkdir -p "$out/bin"
# The executables without their debug info (a fifth of their size), copied into the guest's
# memory there.
for file in "$target/debug/armgate-sim" "$target/debug/armgate" "$target/debug/armgate-firmware" "$e2e"; do
    strip --strip-debug -o "$out/bin/${file##*/}" "$file"
done
started=$SECONDS
echo "socketcan-vm: booting $kernel (TCG) with two kvaser_pci controllers on one QEMU CAN bus"
vm_status=0
# The guest keeps time by the instructions it executes (-icount shift=0: one a nanosecond;
# sleep=off: idle time is skipped), not by the host's clock. The controller and the drives keep
# time (a PT point is needed within a period of being sent, a reply within 50 ms): with the
# guest on the host's clock, a 2-core host busy with other work took the emulated machine away
# for tenths of a second at a time (the Whistle simulator's loop: turns up to 1.1 s late, the
# controller 271 ticks late in 40 s) and the drives faulted (ER33, ER30, ER36) in every run. On
# its own clock the guest only runs slower or faster in wall time, never stalls in its own.
# One vCPU: with two, QEMU writes a frame into the receiving emulated SJA1000's 64-byte FIFO
# from the sending vCPU's thread while the receiving one, which drains it, may not be running,
# and it overran (1 to 6 % of the frames lost, each a lost PT point or reply: a drive fault); on
# one vCPU the receiving interrupt runs before the sender writes again (0 overruns). -icount
# needs a single TCG thread anyway.
# tsc=reliable: otherwise the kernel checks the TSC against the HPET and may fall back to it
# (every clock read an emulated device access).
PATH=$venv/bin:$PATH timeout 600 nice -n -19 vng -r "$kernel" --disable-kvm --cpus 1 --memory 1G --user root \
    --append "tsc=reliable clocksource=tsc" \
    --rwdir "$out" \
    --qemu-opts="-icount shift=0,sleep=off -object can-bus,id=canbus0 -device kvaser_pci,canbus=canbus0 -device kvaser_pci,canbus=canbus0" \
    -- bash "$PWD/tools/socketcan-vm.sh" --inside "$out" "$target/debug" "$e2e" "$e2e_tests" </dev/null 2>&1 |
    while IFS= read -r line; do # each line with the host's seconds since the boot began
        printf '[%3d s] %s\n' $((SECONDS - started)) "$line"
    done | tee "$out/console.txt" || vm_status=$?
if [[ ! -s "$out/console.txt" && -f "$out/vm.txt" ]]; then
    echo "socketcan-vm: (the VM's output, from $out/vm.txt)"
    cat "$out/vm.txt"
fi
echo "socketcan-vm: the VM ran $((SECONDS - started)) s (exit code $vm_status)"
if [[ ! -f "$out/passed" ]]; then
    echo "socketcan-vm: the tests in the VM failed (above)"
    exit 1
fi

decoded=$SECONDS
# The capture, decoded on the host (faster than in the VM): every data frame by both dissectors.
# Error frames (the driver's reports of receive overruns) are counted apart.
capture=$out/can0.pcapng
decode() { tshark -r "$capture" "$@" 2>/dev/null | wc -l; }
frames=$(decode -Y "can.flags.err == 0")
errors=$(decode -Y "can.flags.err == 1")
canopen=$(decode -d can.subdissector,canopen -Y "can.flags.err == 0 && canopen")
lua=$(decode -X lua_script:tools/wireshark/armgate.lua -Y "can.flags.err == 0 && armgate_can")
malformed=$(decode -d can.subdissector,canopen -Y _ws.malformed)
echo "socketcan-vm: capture on can0: $frames data frames (and $errors error frames); Wireshark's CANopen dissector decoded $canopen ($malformed malformed), tools/wireshark/armgate.lua $lua"
tshark -r "$capture" -X lua_script:tools/wireshark/armgate.lua -Y armgate_can -T fields \
    -e armgate_can.service 2>/dev/null | sort | uniq -c | sort -rn | head -n 12
if [[ $frames -lt 200 || $canopen -ne $frames || $lua -ne $frames || $malformed -ne 0 ]]; then
    echo "socketcan-vm: not every captured frame was decoded"
    exit 1
fi
echo "socketcan-vm: passed in $((SECONDS - step_started)) s (installs and builds $((built - step_started)) s, the VM $((decoded - started)) s, the decode $((SECONDS - decoded)) s)"
