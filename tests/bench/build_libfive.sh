#!/bin/sh
# build_libfive.sh — builds bench_equal_error.py's peer: libfive's core library (libfive.so
# alone: no Studio, no Guile or Python bindings, no tests), Release, from a source checkout in
# a scratch folder. Nothing of libfive is part of isomesh; the bench compiles
# libfive_mesher.cc against this build when it finds it.
#
#   git clone https://github.com/libfive/libfive DIR
#   tests/bench/build_libfive.sh [DIR]      DIR: default $LIBFIVE_DIR, else /work/scratch/libfive
#
# LIBFIVE_MARCH (default x86-64-v2) sets -march: libfive's CMakeLists.txt adds -march=native
# when the compiler takes it, and on a CPU with AVX-512 valgrind (3.19) cannot run that code,
# so bench_equal_error.py --instructions could not count it. MARCH_SUPPORTED=OFF answers that
# check beforehand. The bench reads the flag back from the CMake cache and compiles
# libfive_mesher.cc with it (Eigen's alignment, hence libfive::Mesh's layout, must match).
set -eu
dir=${1:-${LIBFIVE_DIR:-/work/scratch/libfive}}
march=${LIBFIVE_MARCH:-x86-64-v2}
# Debian packages the library needs (Eigen, Boost's interval arithmetic, libpng) and the tools.
need="cmake make g++ pkg-config libeigen3-dev libboost-dev libpng-dev"

missing=""
for p in $need; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' ||
        missing="$missing $p"
done
if [ -n "$missing" ]; then
    echo "build_libfive.sh: missing Debian packages; run: apt-get install -y$missing" >&2
    exit 1
fi
if [ ! -f "$dir/CMakeLists.txt" ] || [ ! -d "$dir/libfive" ]; then
    echo "build_libfive.sh: no libfive source in $dir" \
         "(git clone https://github.com/libfive/libfive $dir)" >&2
    exit 1
fi
cmake -S "$dir" -B "$dir/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="-march=$march" \
      -DMARCH_SUPPORTED=OFF -DBUILD_STUDIO_APP=OFF -DBUILD_GUILE_BINDINGS=OFF \
      -DBUILD_PYTHON_BINDINGS=OFF -DBUILD_TESTS=OFF
cmake --build "$dir/build" --target libfive -j "${JOBS:-2}"
echo "build_libfive.sh: $dir/build/libfive/src/libfive.so (-march=$march)"
