#!/bin/sh
# run-tests.sh — runs each test program given, reads cmocka's closing lines, and prints one
# summary line "tests: N passed, N failed, N skipped". Exits non-zero if any test failed or was
# skipped (a skipped test is never counted as passed), or if a program crashed or printed no
# cmocka summary.
passed=0
failed=0
skipped=0
broken=""
for program in "$@"; do
    echo "== $program"
    log=$(mktemp)
    "$program" 2>&1 | tee "$log"
    status=$?
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    s=$(sed -n 's/^\[  SKIPPED \] \([0-9]*\) test.*/\1/p' "$log" | awk '{s+=$1} END {print s+0}')
    if ! grep -q '^\[==========\] [0-9]* test(s) run\.' "$log"; then
        broken="$broken $program"
    fi
    rm -f "$log"
    passed=$((passed + p))
    failed=$((failed + f))
    skipped=$((skipped + s))
done
for program in $broken; do
    echo "run-tests: $program did not finish (crashed or printed no cmocka summary)"
    failed=$((failed + 1))
done
echo "tests: $passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$skipped" -eq 0 ]
