#!/usr/bin/env bash
# Builds the bare-metal benchmarks and runs them in QEMU; prints their tables: instructions per
# call of FK and tracking IK (armgate-qemu-bench), then per full control tick (armgate-qemu-tick),
# then per jerk-limited profile (armgate-qemu-profile).
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
executables=$(cargo build -p armgate-qemu-bench --target "$target" --release \
        --message-format=json-render-diagnostics |
      sed -n 's/.*"executable":"\([^"]*\)".*/\1/p')

status=0
for name in armgate-qemu-bench armgate-qemu-tick armgate-qemu-profile; do
    elf=$(grep "/$name\$" <<<"$executables" | tail -n 1 || true)
    if [[ -z "$elf" || ! -f "$elf" ]]; then
        echo "run.sh: cannot find the $name executable after the build" >&2
        exit 1
    fi
    [[ $name == armgate-qemu-bench ]] || echo
    run=0
    timeout "${QEMU_TIMEOUT:-300}" qemu-system-arm -machine mps2-an500 -cpu cortex-m7 -nographic \
        -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf" || run=$?
    if [[ $run -eq 124 ]]; then
        echo "run.sh: $name: QEMU did not finish within ${QEMU_TIMEOUT:-300} s" >&2
    elif [[ $run -ne 0 ]]; then
        echo "run.sh: $name failed (QEMU exit status $run)" >&2
    fi
    [[ $status -ne 0 ]] || status=$run
done
exit "$status"
