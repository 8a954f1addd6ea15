#!/usr/bin/env bash
# armgate over a real Linux CAN stack, in a VM (issue 36; docs/drives.md, "SocketCAN in a VM"):
#
#   tools/socketcan-vm.sh            (as root: it installs Debian packages and a PyPI venv)
#
# The host's kernel may have no SocketCAN at all; Debian's own kernel has. This boots it with
# virtme-ng over the host's file system (QEMU's TCG, no KVM needed) with two emulated Kvaser PCI
# controllers (kernel driver kvaser_pci/sja1000) on one emulated CAN bus, can0 and can1, and in
# the VM:
#   1. shows the kernel, the driver of each interface and the README's `ip link` recipe
#      ("SocketCAN setup") run verbatim, bit rate and queue length read back;
#   2. ENOBUFS: armgate-sim on can0 left at the default txqueuelen of 10 for a few seconds,
#      its exit summary and the drive state printed (what the README says must happen);
#   3. the end-to-end tests of tests/e2e.rs with ARMGATE_E2E_CAN=can0,can1: each test's
#      armgate-sim on can0 (`--can socketcan:can0`), its Whistles on can1 (`armgate-sim
#      --whistles`): start-up, Cartesian and joint moves, ST at cruise, the PDO schedule, a drive
#      emergency and the Whistles killed mid-move; can0 captured with dumpcap meanwhile;
#   4. `ip -s -d link` of both interfaces (frames counted by the kernel).
# Back on the host, the capture is decoded frame by frame by Wireshark's CANopen dissector and by
# tools/wireshark/armgate.lua: every frame must be decoded by both.
# QEMU's CAN bus has no bit timing: frames cross it as fast as the emulation runs, so this proves
# the stack (sockets, driver, queue, frames, faults), not bus load or latency.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# -- inside the VM -------------------------------------------------------------------------------
if [[ "${1:-}" == "--inside" ]]; then
    out=$2 tests=$3 bin=$4
    export TMPDIR=$out/tmp
    mkdir -p "$TMPDIR"
    sim=$bin/armgate-sim client=$bin/armgate
    robot=robots/ranger-mk1.toml
    echo "kernel: $(uname -r)"
    for iface in can0 can1; do
        driver=$(basename "$(readlink "/sys/class/net/$iface/device/driver")")
        echo "$iface: kernel driver $driver ($(modinfo -F description "$driver" 2>/dev/null || true))"
    done
    lsmod | awk 'NR > 1 && $1 ~ /^(kvaser_pci|sja1000|can_dev|can_raw|can)$/ { print "module " $1 }'

    # The README's recipe, verbatim but for `sudo` (root here), for can0 and can1.
    recipe=$(awk '/^\*\*SocketCAN setup\.\*\*/ { found = 1 } found && /^```sh$/ { inside = 1; next }
        inside && /^```$/ { exit } inside { print }' README.md)
    [[ -n "$recipe" ]] || { echo "socketcan-vm: no recipe in README.md's SocketCAN setup"; exit 1; }
    echo "the README's recipe:"
    echo "$recipe" | sed 's/^/    /'
    setup() { # IFACE [grep -v PATTERN]: the recipe for IFACE, leaving out lines matching PATTERN
        echo "$recipe" | sed "s/can0/$1/g; s/^sudo //" | grep -v -e "${2:-^$}" | bash -eu
    }

    # 2. ENOBUFS: the recipe without its txqueuelen line on can0 (the kernel's default, 10).
    setup can0 txqueuelen
    setup can1
    ip -d link show can0 | sed -n '1p; /bitrate/p'
    chrt -f 20 "$sim" --whistles --can socketcan:can1 --robot "$robot" --duration 14 </dev/null 2>"$out/enobufs-whistles.txt" &
    whistles=$!
    sleep 2
    chrt -f 20 "$sim" --can socketcan:can0 --robot "$robot" --quiet --duration 8 2>"$out/enobufs-sim.txt" &
    controller=$!
    sleep 4
    for _ in 1 2 3 4 5; do
        answer=$("$client" --timeout 1s status 2>&1) && break
        sleep 1
    done
    echo "armgate-sim on can0 with txqueuelen 10: armgate status: $(echo "$answer" | tr '\n' ' ')"
    ps -o pid,etime,time,args -p "$controller,$whistles" | cut -c1-120
    wait "$controller" || true
    kill "$whistles" 2>/dev/null || true
    wait "$whistles" 2>/dev/null || true
    sed 's/^/    /' "$out/enobufs-sim.txt"

    # The recipe in full: txqueuelen 1000.
    setup can0
    ip -d link show can0 | sed -n '1p; /bitrate/p'

    # 3. The end-to-end tests, can0 captured.
    dumpcap -q -i can0 -w "$out/can0.pcapng" 2>"$out/dumpcap.txt" &
    dumpcap=$!
    sleep 1
    status=0
    # Real-time priority in the guest for the tests and the processes they start: the drives
    # and the controller keep time, the rest of the guest can wait.
    ARMGATE_E2E_CAN=can0,can1 ARMGATE_E2E_SIM=$sim chrt -f 20 "$tests" --test-threads 1 --exact \
        a_full_session_over_udp \
        the_pdo_schedule_runs_a_session \
        st_at_cruise_brings_the_arm_to_rest_within_its_acceleration_limits \
        socketcan::an_emergency_from_a_drive_on_the_bus_stops_the_arm_and_on_starts_it_again \
        socketcan::the_whistles_killed_mid_move_stop_the_arm_as_drives_not_answering ||
        status=$?
    sleep 1
    kill -INT "$dumpcap"
    wait "$dumpcap" || true

    # 4. The kernel's counters.
    ip -s -d link show can0
    ip -s -d link show can1
    [[ $status -eq 0 ]] && touch "$out/passed"
    exit 0
fi

# -- on the host ---------------------------------------------------------------------------------
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

# Optimised binaries for the VM (profile `vm`: no LTO): under TCG, and on a machine others share,
# a debug armgate-sim and its simulated Whistles fall behind the wall clock (drives not answering).
cargo build -q --profile vm -p armgate-sim -p armgate-client
tests=$(cargo test -p armgate-sim --test e2e --no-run --message-format=json-render-diagnostics |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | grep "/deps/e2e-" | tail -n 1)
[[ -x "$tests" ]] || { echo "socketcan-vm: no e2e test executable after the build"; exit 1; }

out=$target/socketcan-vm
rm -rf "$out"
mkdir -p "$out"
started=$SECONDS
echo "socketcan-vm: booting $kernel (TCG) with two kvaser_pci controllers on one QEMU CAN bus"
vm_status=0
# The controller and the drives keep time with the wall clock (PT points ahead by a few periods,
# a 50 ms reply timeout): on a 2-core machine busy compiling, an emulated machine at the default
# priority loses whole periods (ER30, ER33). For its two minutes the VM runs at the highest
# priority a `nice` gives (QEMU's -icount, a clock of the guest's own, was tried: too slow).
PATH=$venv/bin:$PATH timeout 600 nice -n -19 vng -r "$kernel" --disable-kvm --cpus 2 --memory 1G --user root \
    --rwdir "$out" \
    --qemu-opts="-object can-bus,id=canbus0 -device kvaser_pci,canbus=canbus0 -device kvaser_pci,canbus=canbus0" \
    -- bash "$PWD/tools/socketcan-vm.sh" --inside "$out" "$tests" "$target/vm" </dev/null || vm_status=$?
echo "socketcan-vm: the VM ran $((SECONDS - started)) s (exit code $vm_status)"
if [[ ! -f "$out/passed" ]]; then
    echo "socketcan-vm: the tests in the VM failed (above)"
    exit 1
fi

# ENOBUFS as the README says: frames refused by the full queue are drive faults (ER35).
refused=$(sed -n 's/.* \([0-9]*\) frames refused by a full transmit queue.*/\1/p' "$out/enobufs-sim.txt")
echo "socketcan-vm: txqueuelen 10: $refused frames refused by a full transmit queue"

# The capture, decoded on the host (faster than in the VM): every frame by both dissectors.
capture=$out/can0.pcapng
frames=$(tshark -r "$capture" 2>/dev/null | wc -l)
canopen=$(tshark -r "$capture" -d can.subdissector,canopen -Y canopen 2>/dev/null | wc -l)
lua=$(tshark -r "$capture" -X lua_script:tools/wireshark/armgate.lua -Y armgate_can 2>/dev/null | wc -l)
malformed=$(tshark -r "$capture" -d can.subdissector,canopen -Y _ws.malformed 2>/dev/null | wc -l)
echo "socketcan-vm: capture on can0: $frames frames; Wireshark's CANopen dissector decoded $canopen ($malformed malformed), tools/wireshark/armgate.lua $lua"
tshark -r "$capture" -d can.subdissector,canopen 2>/dev/null | awk '{ $1 = $2 = ""; print }' |
    sed -E 's/ +/ /g' | sort | uniq -c | sort -rn | head -n 12
tshark -r "$capture" -X lua_script:tools/wireshark/armgate.lua -T fields -e armgate_can.service 2>/dev/null |
    sort | uniq -c | sort -rn | head -n 12
if [[ $frames -lt 1000 || $canopen -ne $frames || $lua -ne $frames || $malformed -ne 0 ]]; then
    echo "socketcan-vm: not every captured frame was decoded"
    exit 1
fi
echo "socketcan-vm: passed"
