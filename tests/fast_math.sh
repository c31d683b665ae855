#!/bin/sh
# lib/core/no_fast_math.h refuses -ffast-math and -ffinite-math-only: a one-line file that
# includes it must compile without them (the control) and fail with each of them, with the
# header's message. Usage: fast_math.sh CC HEADER
set -u
cc=$1 header=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '#include "%s"\nint ap_fast_math_probe(void) { return 0; }\n' "$header" >"$tmp/probe.c"
fail=0
if ! "$cc" -c -o "$tmp/probe.o" "$tmp/probe.c" 2>"$tmp/log"; then
  echo "fast_math: the control compile (no flag) failed:"; cat "$tmp/log"; fail=1
fi
for flag in -ffast-math -ffinite-math-only "-O2 -ffast-math"; do
  # shellcheck disable=SC2086
  if "$cc" $flag -c -o "$tmp/probe.o" "$tmp/probe.c" 2>"$tmp/log"; then
    echo "fast_math: compiling with $flag succeeded; it must fail"; fail=1
  elif ! grep -q "must not be built with -ffast-math" "$tmp/log"; then
    echo "fast_math: compiling with $flag failed without the header's message:"; cat "$tmp/log"
    fail=1
  else
    echo "fast_math: $flag refused: $(grep -o 'Appell must not be built[^:]*' "$tmp/log" | head -n 1)"
  fi
done
exit $fail
