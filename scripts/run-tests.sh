#!/bin/sh
# run-tests.sh — runs each test program given, reads cmocka's lines, and prints one summary line
# "tests: N passed, N failed, N skipped". A program may run several cmocka groups (the device
# tests run one group per OpenCL device, tests/device_test.h): their counts are summed.
#
# Exits non-zero if any test failed or was skipped (a skipped test is never counted as passed).
# A program also counts as one failed test when it did not finish: it crashed or exited non-zero
# without a failed test to show for it, it printed no cmocka summary, a group it started printed
# no summary, or a group's setup or teardown failed (cmocka prints "[  FAILED  ] GROUP SETUP"
# and counts no test). Exit status 77 without a cmocka line counts as one skipped test.
passed=0
failed=0
skipped=0
broken=""
for program in "$@"; do
    echo "== $program"
    log=$(mktemp)
    { "$program" 2>&1; echo "run-tests: exit status $?" >"$log.status"; } | tee "$log"
    status=$(sed -n 's/^run-tests: exit status \([0-9]*\)$/\1/p' "$log.status")
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    s=$(sed -n 's/^\[  SKIPPED \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    started=$(grep -c '^\[==========\] Running [0-9]* test(s)\.' "$log")
    finished=$(grep -c '^\[==========\] [0-9]* test(s) run\.' "$log")
    fixtures=$(grep -c '^\[  FAILED  \] GROUP \(SETUP\|TEARDOWN\)' "$log")
    if [ "${status:-1}" -eq 77 ] && [ "$finished" -eq 0 ]; then
        s=$((s + 1))
    elif [ "$finished" -eq 0 ] || [ "$started" -ne "$finished" ] || [ "$fixtures" -ne 0 ] ||
        { [ "${status:-1}" -ne 0 ] && [ "$f" -eq 0 ]; }; then
        broken="$broken $program(exit=${status:-none},groups=$finished/$started)"
    fi
    rm -f "$log" "$log.status"
    passed=$((passed + p))
    failed=$((failed + f))
    skipped=$((skipped + s))
done
for program in $broken; do
    echo "run-tests: $program did not finish (crashed, exited non-zero without a failed test, a group's setup or teardown failed, or printed no cmocka summary)"
    failed=$((failed + 1))
done
echo "tests: $passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$skipped" -eq 0 ]
