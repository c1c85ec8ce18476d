#!/usr/bin/env bash
# The test command: installs dependencies, builds, and runs every test under ctest; then the same
# suite built with AddressSanitizer + UndefinedBehaviorSanitizer (build-asan, NDFBAKE_SANITIZE);
# then each libFuzzer target for a short while (build-fuzz, when clang and libFuzzer are installed).
#   NDFBAKE_SANITIZE_TESTS=0   skip the sanitizer build
#   NDFBAKE_FUZZ_SECONDS=N     seconds per fuzz target (default 20; 0 skips fuzzing)
#   NDFBAKE_FUZZ_SEED=N        libFuzzer's seed (default 1, so that every run replays the corpus and
#                              then tries the same mutations: the test command fails for a
#                              regression, not for what a random seed happened to find; 0 picks
#                              a random seed, as `scripts/fuzz.sh TARGET 600` campaigns do)
set -euo pipefail
# Debian's own tools first: a Python manager's shims ahead of /usr/bin (pyenv's cmake and ctest) would
# hand the tests its interpreter, and Debian's Blender would then find that Python's home, not its own.
export PATH=/usr/sbin:/usr/bin:/sbin:/bin:$PATH
root=$(cd "$(dirname "$0")/.." && pwd)
start=$SECONDS
stage() { echo "== test.sh: $1 ($((SECONDS - start)) s so far)"; }

bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh"
build=${NDFBAKE_BUILD_DIR:-$root/build}
stage "ctest (build): native tests and Debian's Blender $(blender --version 2>/dev/null | head -1 | cut -d' ' -f2)"
(cd "$build" && ctest --output-on-failure -j "$(nproc)" -LE 'bpy-|debian13|windows-')
stage "ctest (build): Debian 13's Blender 4.3 (chroot)"
(cd "$build" && ctest --output-on-failure -j "$(nproc)" -L debian13)
# The Blender tests again in each bpy series installed (tests/CMakeLists.txt: NDFBAKE_BPY_SERIES).
for series in $(cd "$build" && ctest -N --print-labels | sed -n 's/^ *bpy-//p'); do
  stage "ctest (build): Blender $series (bpy module)"
  (cd "$build" && ctest --output-on-failure -j "$(nproc)" -L "bpy-$series\$")
done
# And in each Windows bpy series under wine (NDFBAKE_TEST_WINDOWS_BPY_SERIES).
for series in $(cd "$build" && ctest -N --print-labels | sed -n 's/^ *windows-//p'); do
  stage "ctest (build): Windows Blender $series (bpy module under wine)"
  (cd "$build" && ctest --output-on-failure -j "$(nproc)" -L "windows-$series\$")
done

if [ "${NDFBAKE_SANITIZE_TESTS:-1}" != 0 ]; then
  # Every test again with ASan + UBSan; any report fails it (tests/CMakeLists.txt sets the
  # options and tests/lsan.supp). The Blender tests load the library into Blender itself, which
  # cannot take an ASan-instrumented library, so they run in the plain build only.
  asan=${NDFBAKE_ASAN_BUILD_DIR:-$root/build-asan}
  stage "sanitizer build ($asan)"
  cmake -S "$root" -B "$asan" -DCMAKE_BUILD_TYPE=Release -DNDFBAKE_SANITIZE=ON >/dev/null
  cmake --build "$asan" -j "$(nproc)"
  stage "ctest (sanitizer build)"
  (cd "$asan" && ctest --output-on-failure -j "$(nproc)" -LE blender)
fi

fuzz_seconds=${NDFBAKE_FUZZ_SECONDS:-20}
if [ "$fuzz_seconds" != 0 ]; then
  if bash "$root/scripts/fuzz.sh" --check; then
    for target in decode bake tangent; do
      stage "fuzz $target"
      NDFBAKE_FUZZ_KEEP=0 bash "$root/scripts/fuzz.sh" "$target" "$fuzz_seconds" -seed="${NDFBAKE_FUZZ_SEED:-1}"
    done
  else
    echo "== test.sh: fuzzing skipped: clang++ with libFuzzer is not installed (apt-get install clang libclang-rt-14-dev)"
  fi
fi
stage "all passed"
