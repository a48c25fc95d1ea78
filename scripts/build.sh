#!/bin/sh
# Configures and builds Fountain in ./build (Release), or in $BUILD_DIR with extra cmake flags;
# $TARGET builds one target only.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=${BUILD_TYPE:-Release} "$@" > "$build.cmake.log" 2>&1 \
  || { cat "$build.cmake.log"; exit 1; }
if [ -n "${TARGET:-}" ]; then
  cmake --build "$build" -j "${JOBS:-2}" --target "$TARGET"
else
  cmake --build "$build" -j "${JOBS:-2}"
fi
