#!/bin/sh
# fuzz/run.sh [SECONDS] - builds the libFuzzer targets with clang
# (-fsanitize=fuzzer,address,undefined, the C path) and runs each for
# SECONDS (default 60; 0 replays the seed corpus only), after replaying
# every input in fuzz/regress/.
#
# Each input has a time limit (-timeout, 10 s) and a memory limit
# (-rss_limit_mb 2048, -malloc_limit_mb 1024): a slow or hungry input is a
# finding like a crash. The seed corpus is fuzz/corpus/<target>/ (read
# only); what a run adds goes to $FUZZ_OUT (default fuzz-out/ in the build
# folder), findings to $FUZZ_OUT/artifacts/. Exit status non-zero on any
# finding. Run from the build folder (it needs config.h), after configure.
set -eu
secs=${1:-60}
src=$(cd "$(dirname "$0")/.." && pwd)
build=$(pwd)
out=${FUZZ_OUT:-$build/fuzz-out}
cc=${FUZZ_CC:-clang}
san="-fsanitize=address,undefined -fno-sanitize-recover=undefined"
[ -f "$build/config.h" ] || { echo "fuzz/run.sh: no config.h here: run it from a configured build folder" >&2; exit 2; }
command -v "$cc" >/dev/null || { echo "fuzz/run.sh: $cc not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }

mkdir -p "$out/obj" "$out/artifacts"
cflags="-g -O1 -std=c11 -D_GNU_SOURCE -fno-omit-frame-pointer $san
  -I$build -I$src/src/core -I$src/src/cl -I$src/src/gdal $(gdal-config --cflags)"
objs=""
for f in "$src"/src/core/*.c "$src"/src/gdal/wm_options.c \
  "$src"/src/gdal/wm_ingest.c "$src"/src/gdal/wm_device.c \
  "$src"/src/gdal/wm_run.c "$src"/src/gdal/wm_shard.c \
  "$src"/src/gdal/wm_drape.c \
  "$src"/src/cl/wm_cl_none.c; do
  o="$out/obj/$(basename "$f" .c).o"
  # rebuilt when its source or any header is newer
  if [ ! -f "$o" ] || [ "$f" -nt "$o" ] ||
    [ -n "$(find "$src/src" "$src/fuzz" -name '*.h' -newer "$o" | head -1)" ]; then
    # shellcheck disable=SC2086
    $cc $cflags -fsanitize=fuzzer-no-link -c "$f" -o "$o"
  fi
  objs="$objs $o"
done

status=0
for t in options descriptor scene; do
  bin="$out/fuzz_$t"
  # shellcheck disable=SC2086
  $cc $cflags -fsanitize=fuzzer "$src/fuzz/fuzz_$t.c" $objs \
    $(gdal-config --libs) -lpthread -lm -o "$bin"
  opts="-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=4096"
  # every earlier finding, replayed once
  if [ -d "$src/fuzz/regress/$t" ] && [ -n "$(ls -A "$src/fuzz/regress/$t")" ]; then
    # shellcheck disable=SC2086
    if ! "$bin" $opts "$src/fuzz/regress/$t"/* >"$out/$t.regress.log" 2>&1; then
      echo "fuzz $t: a regression input fails again:" >&2
      tail -30 "$out/$t.regress.log" >&2
      status=1
      continue
    fi
    echo "fuzz $t: $(ls "$src/fuzz/regress/$t" | wc -l) regression inputs pass"
  fi
  mkdir -p "$out/corpus/$t"
  dict=""
  [ -f "$src/fuzz/$t.dict" ] && dict="-dict=$src/fuzz/$t.dict"
  if [ "$secs" -gt 0 ]; then
    length="-max_total_time=$secs"
  else
    length="-runs=0" # the corpus, replayed once
  fi
  # shellcheck disable=SC2086
  if "$bin" $opts $dict $length -print_final_stats=1 \
    -artifact_prefix="$out/artifacts/$t-" "$out/corpus/$t" \
    "$src/fuzz/corpus/$t" >"$out/$t.log" 2>&1; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$out/$t.log")
    cov=$(grep -o 'cov: [0-9]*' "$out/$t.log" | tail -1)
    echo "fuzz $t: ${secs} s, $runs inputs, $cov edges, no finding"
  else
    echo "fuzz $t: FINDING (artifacts in $out/artifacts/):" >&2
    tail -40 "$out/$t.log" >&2
    status=1
  fi
done
exit $status
