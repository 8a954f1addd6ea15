#!/usr/bin/env bash
# Builds the bare-metal kinematics benchmark and runs it in QEMU; prints its table.
#
#   qemu-bench/run.sh            (from anywhere; honours CARGO_TARGET_DIR)
#
# The build is a cargo call of its own: built together with the firmware, embassy-stm32 would
# switch on cortex-m-rt's `device` feature, and this binary (no device crate) would not link.
# QEMU is called directly (the workspace's runner for the thumb target is probe-rs, for the board).
# -icount shift=0 makes virtual time advance 1 ns per instruction: the figures are instruction
# counts, the same on every host. QEMU_TIMEOUT (seconds, default 300) bounds the run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

target=thumbv7em-none-eabihf
elf=$(cargo build -p armgate-qemu-bench --target "$target" --release \
        --message-format=json-render-diagnostics |
      sed -n 's/.*"executable":"\([^"]*armgate-qemu-bench\)".*/\1/p' | tail -n 1)
if [[ -z "$elf" || ! -f "$elf" ]]; then
    echo "run.sh: cannot find the armgate-qemu-bench executable after the build" >&2
    exit 1
fi

status=0
timeout "${QEMU_TIMEOUT:-300}" qemu-system-arm -machine mps2-an500 -cpu cortex-m7 -nographic \
    -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf" || status=$?
if [[ $status -eq 124 ]]; then
    echo "run.sh: QEMU did not finish within ${QEMU_TIMEOUT:-300} s" >&2
elif [[ $status -ne 0 ]]; then
    echo "run.sh: the benchmark failed (QEMU exit status $status)" >&2
fi
exit "$status"
