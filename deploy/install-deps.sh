#!/bin/sh
# install-deps.sh — installs, with apt-get, the Debian 12 packages that building, testing,
# benchmarking and serving isomesh need, and nothing that is already there (idempotent).
#
#   deploy/install-deps.sh [run|test|bench|all]   install what that purpose needs (default: test)
#   deploy/install-deps.sh --check [PURPOSE]      exit 0 when nothing is missing, 1 otherwise
#
# Without root it prints the exact apt-get line to run and exits 1.
set -eu

purpose=test
check_only=0
for arg in "$@"; do
    case "$arg" in
        --check) check_only=1 ;;
        run|test|bench|all) purpose=$arg ;;
        -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
        *) echo "install-deps.sh: unknown argument '$arg' (try --help)" >&2; exit 2 ;;
    esac
done

# Build and serve: compiler, pkg-config, the libraries the daemon links, node for the viewer.
run_pkgs="build-essential pkg-config libmicrohttpd-dev libdraco-dev libjansson-dev
libsodium-dev libseccomp-dev libhiredis-dev zlib1g-dev nodejs npm ca-certificates"
# Tests: unit-test framework, Draco's own decoder, sanitizer/fuzzer runtime, a browser,
# Python for HTTP tests, the servers the deploy tests start, load and leak tools.
test_pkgs="libcriterion-dev draco clang libclang-rt-14-dev chromium python3 redis-server
nginx-light wrk valgrind systemd fonts-dejavu-core openssl stunnel4"
# Reference tools the benchmarks measure beside isomesh.
bench_pkgs="python3-skimage python3-numpy python3-vtk9 libcgal-dev libgmp-dev libmpfr-dev hyperfine"

case "$purpose" in
    run) want=$run_pkgs ;;
    test) want="$run_pkgs $test_pkgs" ;;
    bench) want="$run_pkgs $bench_pkgs" ;;
    all) want="$run_pkgs $test_pkgs $bench_pkgs" ;;
esac

installed() {
    dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'
}

missing=""
for p in $want; do
    # node and npm may come from outside Debian (nodesource, nvm): accept the commands.
    case "$p" in
        nodejs) command -v node >/dev/null 2>&1 && continue ;;
        npm) command -v npm >/dev/null 2>&1 && continue ;;
        nginx-light) { installed nginx || installed nginx-light || installed nginx-core; } && continue ;;
    esac
    installed "$p" || missing="$missing $p"
done

if [ -z "$missing" ]; then
    [ "$check_only" = 1 ] || echo "install-deps: everything for '$purpose' is installed"
    exit 0
fi
if [ "$check_only" = 1 ]; then
    echo "install-deps: missing for '$purpose':$missing" >&2
    exit 1
fi

apt_line="apt-get -o DPkg::Lock::Timeout=600 install -y --no-install-recommends$missing"
if [ "$(id -u)" != 0 ]; then
    echo "install-deps: these packages are missing:$missing" >&2
    echo "install-deps: run as root:  apt-get update && $apt_line" >&2
    exit 1
fi

echo "install-deps: installing$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get -o DPkg::Lock::Timeout=600 update -qq
# shellcheck disable=SC2086
apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends $missing
