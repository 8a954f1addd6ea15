# Sourced by .ci/run and tools/socketcan-vm.sh: installs Debian packages so that a failure ends
# the run at once, with the step that failed, instead of 25 minutes later on a missing tool.
# apt waits up to 10 minutes for a lock another apt holds (an unattended upgrade, a second CI).

# apt_install PACKAGE...: `apt-get update`, then `apt-get install`; exits the caller on failure.
apt_install() {
    export DEBIAN_FRONTEND=noninteractive
    local lock=(-o DPkg::Lock::Timeout=600)
    if ! apt-get "${lock[@]}" update -qq; then
        echo "apt: 'apt-get update' failed (above); cannot install: $*" >&2
        exit 1
    fi
    if ! apt-get "${lock[@]}" install -y -qq "$@" >/dev/null; then
        echo "apt: 'apt-get install $*' failed (above)" >&2
        exit 1
    fi
}
