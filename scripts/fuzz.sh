#!/usr/bin/env bash
# Runs one libFuzzer target (tests/fuzz/fuzz_TARGET.cpp) for SECONDS, building it first if needed
# (clang, ASan + UBSan, into build-fuzz), and keeps the corpus: new inputs that add coverage are
# merged into tests/fuzz/corpus/TARGET (set NDFBAKE_FUZZ_KEEP=0 to leave the tree alone, as the
# test command does). Crash, leak and timeout reproducers go to build-fuzz/artifacts/TARGET/.
#
#   scripts/fuzz.sh decode|bake|tangent SECONDS [libFuzzer flags...]
#   scripts/fuzz.sh --check            exit 0 if clang and libFuzzer are installed
#   scripts/fuzz.sh TARGET 600 -jobs=2 -workers=2    the 10-minute run of the acceptance criteria
#
# Reproduce a finding: build-fuzz/tests/fuzz/fuzz_TARGET build-fuzz/artifacts/TARGET/crash-...
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${NDFBAKE_FUZZ_BUILD_DIR:-$root/build-fuzz}

have_libfuzzer() {
  command -v clang++ >/dev/null 2>&1 || return 1
  local probe
  probe=$(mktemp -d)
  printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' > "$probe/p.cpp"
  local ok=0
  clang++ -fsanitize=fuzzer,address "$probe/p.cpp" -o "$probe/p" >/dev/null 2>&1 || ok=$?  # set -e: no exit
  rm -rf "$probe"
  return $ok
}

if [ "${1:-}" = "--check" ]; then
  have_libfuzzer
  exit $?
fi
if [ $# -lt 2 ]; then
  sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'
  exit 1
fi
target=$1
seconds=$2
shift 2
case "$target" in decode|bake|tangent) ;; *) echo "fuzz.sh: unknown target '$target' (decode, bake, tangent)" >&2; exit 1;; esac
if ! have_libfuzzer; then
  echo "fuzz.sh: clang++ with libFuzzer is not installed (Debian: apt-get install clang libclang-rt-14-dev)" >&2
  exit 2
fi

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
      -DNDFBAKE_FUZZ=ON -DNDFBAKE_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" --target "fuzz_$target" -j "$(nproc)" >/dev/null

seeds="$root/tests/fuzz/corpus/$target"
work="$build/corpus/$target"
artifacts="$build/artifacts/$target"
mkdir -p "$seeds" "$work" "$artifacts"
dict=()
[ -f "$root/tests/fuzz/$target.dict" ] && dict=(-dict="$root/tests/fuzz/$target.dict")

# Full allocation stacks so that tests/lsan.supp (third-party frames only) can match.
export ASAN_OPTIONS="fast_unwind_on_malloc=0:detect_leaks=1:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"

# The files the targets write per input go to a scratch folder of this run, removed at the end.
scratch=$(mktemp -d /dev/shm/ndfbake-fuzz.XXXXXX 2>/dev/null || mktemp -d)
trap 'rm -rf "$scratch"' EXIT
export NDFBAKE_FUZZ_SCRATCH="$scratch"

fuzzer="$build/tests/fuzz/fuzz_$target"
echo "fuzz.sh: $target for ${seconds}s (seeds: tests/fuzz/corpus/$target, $(ls "$seeds" | wc -l) files)"
status=0
(cd "$artifacts" && "$fuzzer" "$work" "$seeds" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=3072 \
   -max_len=65536 -print_final_stats=1 -artifact_prefix="$artifacts/" "${dict[@]}" "$@") \
  > "$build/fuzz-$target.log" 2>&1 || status=$?
grep -E "^stat::(number_of_executed_units|peak_rss_mb|new_units_added)|^(==[0-9]+==ERROR|SUMMARY|Done)" \
  "$build/fuzz-$target.log" || true
if [ $status -ne 0 ]; then
  tail -n 60 "$build/fuzz-$target.log" >&2
  echo "fuzz.sh: $target FAILED (log: $build/fuzz-$target.log, reproducer in $artifacts)" >&2
  exit $status
fi
if [ "${NDFBAKE_FUZZ_KEEP:-1}" != 0 ]; then
  # Keep what adds coverage: a minimal merge of the run's inputs into the seed corpus.
  before=$(ls "$seeds" | wc -l)
  "$fuzzer" -merge=1 "$seeds" "$work" -rss_limit_mb=3072 -timeout=30 > "$build/merge-$target.log" 2>&1
  echo "fuzz.sh: corpus tests/fuzz/corpus/$target: $before -> $(ls "$seeds" | wc -l) files"
fi
echo "fuzz.sh: $target passed"
