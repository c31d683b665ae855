#!/usr/bin/env bash
# The installed library and tool work outside the build tree (meson test 'install').
#
#   tests/install.sh BUILD_DIR SOURCE_DIR
#
# Installs BUILD_DIR into a temporary DESTDIR (meson install --destdir, no rebuild), then:
#   - pkg-config finds appell.pc there and its --cflags --libs build examples/rolling_disk.c
#     (public API only) copied outside the tree; the program runs and exits 0;
#   - the installed appell finds the installed libappell.so.0 through its own rpath (no
#     LD_LIBRARY_PATH): `appell --version` prints pkg-config's version, `appell check` accepts
#     examples/scenes/rolling_disk.yaml.
# Prints what it does; exits non-zero on the first failure.
set -euo pipefail

build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
unset LD_LIBRARY_PATH

fail() {
  echo "install: FAILED: $*" >&2
  exit 1
}

meson install -C "$build" --destdir "$tmp/root" --no-rebuild --quiet >/dev/null ||
  fail "meson install --destdir"
pc=$(find "$tmp/root" -name appell.pc -print -quit)
[[ -n "$pc" ]] || fail "no appell.pc installed"
prefix=$(sed -n 's/^prefix=//p' "$pc")
root="$tmp/root$prefix"
echo "install: $(find "$tmp/root" -type f | wc -l) files under $root, $pc"

export PKG_CONFIG_PATH="$(dirname "$pc")"
flags=$(pkg-config --define-variable=prefix="$root" --cflags --libs appell) ||
  fail "pkg-config --cflags --libs appell"
libdir=$(pkg-config --define-variable=prefix="$root" --variable=libdir appell)
echo "install: pkg-config --cflags --libs appell: $flags"

cp "$src/examples/rolling_disk.c" "$tmp/prog.c"
# shellcheck disable=SC2086  # flags are words
"${CC:-cc}" -std=c11 -D_POSIX_C_SOURCE=200809L "$tmp/prog.c" -o "$tmp/prog" $flags -lm \
  -Wl,-rpath,"$libdir" || fail "building a program with pkg-config's flags"
(cd "$tmp" && OPENBLAS_NUM_THREADS=1 ./prog >/dev/null) || fail "the program built outside the tree"
echo "install: examples/rolling_disk.c built outside the tree with those flags runs"

appell="$root/bin/appell"
deps=$(ldd "$appell")   # whole, not piped into grep -q (pipefail would see ldd's SIGPIPE)
loaded=$(grep libappell <<<"$deps" || true)
[[ "$loaded" == *"libappell.so.0 => $tmp/root"* ]] ||
  fail "the installed appell does not load the installed libappell.so.0: ${loaded:-not found}"
version=$("$appell" --version) || fail "appell --version"
[[ "$version" == "appell $(pkg-config --modversion appell)" ]] ||
  fail "appell --version says '$version', appell.pc says $(pkg-config --modversion appell)"
OPENBLAS_NUM_THREADS=1 "$appell" check "$src/examples/scenes/rolling_disk.yaml" >/dev/null ||
  fail "appell check"
echo "install: the installed appell ($version) loads $(sed -n \
  's/.*libappell.so.0 => \([^ ]*\).*/\1/p' <<<"$loaded" | sed "s|$tmp|DESTDIR|") and checks a scene"
echo "install: passed"
