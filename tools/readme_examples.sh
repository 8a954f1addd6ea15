#!/usr/bin/env bash
# Runs the README's examples against armgate-sim, in the README's order, and fails if any of
# them fails: the quick start (the simulator and the client commands) and every line of the
# client section's example block. The commands are read from README.md itself, so they cannot
# drift from what it says. Run by .ci/run; takes about a minute and a half (the moves run at
# ranger-mk1's 3 cm/s).
#
# The simulator's logs go to a temporary directory instead of logs/, and `armgate plot logs`
# runs on them after the simulator has stopped (its logs are flushed then).
#
# Then the lines of "See the arm" (`armgate urdf`, `armgate record`, the recipe's move).
#
# With ARMGATE_SIGNED=1 the same examples run signed (docs/safety.md, "Signing"): armgate-sim
# gets a fresh key (--key), the client signs with it (ARMGATE_KEY_FILE), the Python client's
# README line runs with `key=`, and at the end the simulator must have dropped nothing.
#
# Not run: `cargo test` (CI's own step), the nightly fuzzer (.ci/run runs it where a nightly
# toolchain and cargo-fuzz are installed), `armgate teleop` (it needs a terminal; tests cover it
# at the state level) and the other armgate-sim lines (python/tests/test_mcap.py records with
# --mcap, tests/foxglove_live.rs views --foxglove).
set -euo pipefail
cd "$(dirname "$0")/.."

readme=README.md
target=${CARGO_TARGET_DIR:-target}
# One package per call, as `cargo run -p ...` in the README builds them (features unify per
# call), so that the README's commands find them built.
cargo build -q -p armgate-sim
cargo build -q -p armgate-client
cargo build -q -p armgate-viz

# `armgate` as the README writes it: the binary just built.
shim=$(mktemp -d)
sim_pid=
cleanup() {
    if [[ -n $sim_pid ]] && kill -0 "$sim_pid" 2>/dev/null; then
        kill "$sim_pid" 2>/dev/null || true
    fi
    rm -rf "$shim"
}
trap cleanup EXIT
ln -s "$(realpath "$target/debug/armgate")" "$shim/armgate"
export PATH="$shim:$PATH"

sim_key=
if [[ ${ARMGATE_SIGNED:-} == 1 ]]; then
    key=$shim/arm.key
    (umask 077 && od -An -N32 -tx1 /dev/urandom | tr -d ' \n' >"$key" && echo >>"$key")
    sim_key="--key $key --state $shim/replay-state"
    export ARMGATE_KEY_FILE=$key
    echo "signed pass: key file $key"
fi

# The non-empty lines of the ```sh blocks under the heading `## $1`, comments removed.
examples() {
    awk -v want="## $1" '
        /^## / { section = $0 }
        /^```sh$/ { inside = (section == want); next }
        /^```/ { inside = 0; next }
        inside {
            sub(/[ \t]+#.*$/, ""); sub(/^#.*$/, "")
            if (NF) print
        }' "$readme"
}

failures=0
run() {
    local cmd=$1 started status
    printf '\n$ %s\n' "$cmd"
    started=$(date +%s%N)
    set +e
    timeout 300 bash -c "$cmd"
    status=$?
    set -e
    local tenths=$((($(date +%s%N) - started) / 100000000))
    printf '(exit %s, %d.%d s)\n' "$status" $((tenths / 10)) $((tenths % 10))
    if [[ $status -ne 0 ]]; then
        echo "FAILED: $cmd" >&2
        failures=$((failures + 1))
    fi
}

quick=$(examples "Quick start")
client=$(examples 'Client: `armgate`')
viz=$(examples 'See the arm: Foxglove, MCAP and URDF')
[[ -n $quick && -n $client && -n $viz ]] || { echo "no examples found in $readme" >&2; exit 1; }

# `armgate calibrate` is how its help names it (it runs armgate-calibrate).
if ! armgate calibrate --help | grep -q '^Usage: armgate calibrate '; then
    echo "FAILED: armgate calibrate --help does not say armgate calibrate" >&2
    failures=$((failures + 1))
fi

# Every `Example:` of a subcommand's --help is one of the README's client or "See the arm"
# examples, so it runs below on the robot the README names.
for sub in $(armgate --help | awk '/^Commands:/ { on = 1; next } /^$/ { on = 0 } on { print $1 }'); do
    # calibrate needs measurements (its own tests run it), help has no --help.
    [[ $sub == calibrate || $sub == help ]] && continue
    example=$(armgate "$sub" --help | sed -n 's/^Example: //p')
    [[ -z $example ]] && continue
    if ! grep -qxF -- "$example" <<<"$(printf '%s\n%s\n' "$client" "$viz" | tr ';' '\n' | sed 's/^ *//; s/ *$//')"; then
        echo "FAILED: the example of \`armgate $sub --help\` is not among the README's: $example" >&2
        failures=$((failures + 1))
    fi
done

# The simulator line of the quick start, on a free port instead of 7031 (`cargo run` replaces
# itself by the binary, so $! is the simulator).
sim=$(grep -m1 -- '-p armgate-sim' <<<"$quick") || { echo "no armgate-sim line" >&2; exit 1; }
log=$shim/sim.log
sim=${sim/--log-dir logs/--log-dir $shim/logs}
echo "\$ $sim --listen 127.0.0.1:0 $sim_key"
bash -c "exec $sim --listen 127.0.0.1:0 $sim_key" 2>"$log" &
sim_pid=$!
for _ in $(seq 600); do
    grep -q 'udp://' "$log" && break
    kill -0 "$sim_pid" 2>/dev/null || { cat "$log" >&2; exit 1; }
    sleep 0.1
done
if ! grep -q 'udp://' "$log"; then
    echo "armgate-sim did not start within 60 s:" >&2
    cat "$log" >&2
    exit 1
fi
ARMGATE_ADDR=$(grep -o 'udp://[^,]*' "$log" | head -1 | cut -c7-)
export ARMGATE_ADDR
echo "armgate-sim listens on $ARMGATE_ADDR"

while IFS= read -r line; do
    case $line in
        *armgate-sim*) ;;                                    # started above
        "cargo test"*) echo "skipped: $line (a CI step of its own)" ;;
        *"cargo +nightly"*) echo "skipped: $line (needs nightly)" ;;
        *teleop*) echo "skipped: $line (needs a terminal)" ;;
        *) run "$line" ;;
    esac
done <<<"$quick"

# Client lines may hold several commands separated by `;`; each runs on its own.
plots=()
while IFS= read -r line; do
    IFS=';' read -ra commands <<<"$line"
    for cmd in "${commands[@]}"; do
        cmd=$(sed 's/^ *//; s/ *$//' <<<"$cmd")
        case $cmd in
            *teleop*) echo "skipped: $cmd (needs a terminal)" ;;
            "armgate plot logs"*) plots+=("${cmd/plot logs/plot $shim/logs}") ;;
            *) run "$cmd" ;;
        esac
    done
done <<<"$client"

# The signed pass: the Python client's README line, with the key.
if [[ -n $sim_key ]]; then
    python=$(examples "Python client" | grep -m1 '^python3') || { echo "no python3 line" >&2; exit 1; }
    port=${ARMGATE_ADDR##*:}
    run "PYTHONPATH=python ${python/port=7031)/port=$port, key=\"$key\")}"
fi

# Ctrl-C during a wait sends ST: the arm stops and holds. (A background job of a script
# ignores SIGINT until armgate installs its handler, as it does before its first request.)
echo
echo '$ armgate mode joint; armgate jmove 1.5708 0 1.5708 0 1.5708 0, Ctrl-C after 2 s'
sleep 0.5 # a controller without SQ cannot say when the drives run after `armgate on`
armgate mode joint >/dev/null
armgate jmove 1.5708 0 1.5708 0 1.5708 0 >"$shim/jmove.out" 2>&1 &
jmove_pid=$!
sleep 2
kill -INT "$jmove_pid" || true
set +e
wait "$jmove_pid"
status=$?
set -e
tail -n 2 "$shim/jmove.out"
sleep 1 # the stop decelerates, and the drives follow a few points behind
before=$(armgate --joints 6 joints)
sleep 1
after=$(armgate --joints 6 joints)
if [[ $status -ne 130 ]] || ! grep -q 'sent ST' "$shim/jmove.out" || [[ $before != "$after" ]]; then
    echo "FAILED: Ctrl-C did not stop the arm (exit $status)" >&2
    printf '%s\n---\n%s\n' "$before" "$after" >&2
    failures=$((failures + 1))
else
    echo "(exit 130; the arm holds)"
fi

# "See the arm": the files they write are removed afterwards.
while IFS= read -r line; do
    IFS=';' read -ra commands <<<"$line"
    for cmd in "${commands[@]}"; do
        cmd=$(sed 's/^ *//; s/ *$//' <<<"$cmd")
        case $cmd in
            *armgate-sim*) echo "skipped: $cmd (the simulator runs; tests record and view it)" ;;
            *) run "$cmd" ;;
        esac
    done
done <<<"$viz"
rm -f ur5.urdf run.mcap

# The simulator ends cleanly on SIGTERM, with its summary.
kill -TERM "$sim_pid"
set +e
wait "$sim_pid"
status=$?
set -e
sim_pid=
tail -n 2 "$log"
if [[ $status -ne 0 ]]; then
    echo "FAILED: armgate-sim exited with $status on SIGTERM" >&2
    failures=$((failures + 1))
fi
if [[ -n $sim_key ]] && ! grep -q 'dropped: 0 unsigned, 0 truncated, 0 forged, 0 replayed' "$log"; then
    echo "FAILED: the signed clients' datagrams were not all served" >&2
    failures=$((failures + 1))
fi

# The plots of the session's logs, now complete.
for cmd in "${plots[@]}"; do
    run "$cmd"
done

if [[ $failures -ne 0 ]]; then
    echo "$failures README example(s) failed" >&2
    exit 1
fi
echo "all README examples ran"
