#!/bin/sh
# run-fuzz.sh SECONDS TARGET... — runs each libFuzzer target (build/fuzz/tests/fuzz_NAME, built
# by `make fuzz`) for SECONDS, one after another, and prints one line per target: executions,
# corpus size, crashes (and leaks), hangs, out-of-memory. Each starts from its seeds in
# tests/fuzz/corpus/NAME and from what earlier runs found (build/fuzz/corpus/NAME, kept between
# runs). A hang is an input that runs longer than 10 s; out-of-memory, one that takes 4 GiB.
#
# Exits non-zero when a target found anything; the input is in build/fuzz/artifacts/NAME/ and
# the target's log in build/fuzz/NAME.log. Once it is fixed, store the input in
# tests/fuzz/regressions/NAME/ (named reject-... when it must be rejected), where
# test_fuzz_inputs replays it in every `make test`.
set -u
seconds=$1
shift
status=0
for target in "$@"; do
    name=$(basename "$target")
    short=${name#fuzz_}
    corpus=build/fuzz/corpus/$short
    artifacts=build/fuzz/artifacts/$short
    log=build/fuzz/$name.log
    rm -rf "$artifacts"
    mkdir -p "$corpus" "$artifacts"
    echo "fuzz $short: running ${seconds} s (log: $log)"
    "$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 \
        -artifact_prefix="$artifacts/" "$corpus" "tests/fuzz/corpus/$short" >"$log" 2>&1
    rc=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    crashes=$(find "$artifacts" -name 'crash-*' -o -name 'leak-*' | wc -l)
    hangs=$(find "$artifacts" -name 'timeout-*' | wc -l)
    ooms=$(find "$artifacts" -name 'oom-*' | wc -l)
    echo "fuzz $short: ${runs:-0} executions, corpus $(find "$corpus" -type f | wc -l) inputs," \
        "crashes $crashes, hangs $hangs, out-of-memory $ooms"
    if [ "$rc" -ne 0 ] || [ $((crashes + hangs + ooms)) -ne 0 ]; then
        echo "fuzz $short: FOUND SOMETHING (exit $rc): see $log and $artifacts/" >&2
        status=1
    fi
done
exit $status
