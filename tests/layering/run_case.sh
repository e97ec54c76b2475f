#!/usr/bin/env bash
# run_case.sh pass|fail TEXT CMAKE CMAKE_ARGS...: configures the fixture with cmake;
# passes when cmake succeeds (pass) or fails (fail) and prints TEXT.
want=$1 text=$2 cmake=$3; shift 3
out=$("$cmake" "$@" 2>&1); rc=$?
echo "$out"
if [ "$want" = pass ] && [ "$rc" -ne 0 ]; then echo "expected cmake to succeed, got exit $rc"; exit 1; fi
if [ "$want" = fail ] && [ "$rc" -eq 0 ]; then echo "expected cmake to stop, got exit 0"; exit 1; fi
grep -qF -- "$text" <<<"$out" || { echo "expected '$text' in the output"; exit 1; }
echo "as expected (cmake exit $rc)"
