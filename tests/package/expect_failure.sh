#!/usr/bin/env bash
# expect_failure.sh TEXT CMD...: passes when CMD exits non-zero and prints TEXT.
text=$1; shift
out=$("$@" 2>&1); rc=$?
echo "$out"
[ "$rc" -ne 0 ] || { echo "expected a failure, got exit 0"; exit 1; }
grep -qF -- "$text" <<<"$out" || { echo "expected '$text' in the output"; exit 1; }
echo "failed as expected (exit $rc)"
