#!/usr/bin/env bash
# make install's result in use: install into a temporary prefix, build a small C program against
# the library with pkg-config and with the CMake package and run both; the installed program
# finds its plotting scripts, and its man page and completion are those of its tables; the
# installed Python package finds its library.
#   usage: install_test.sh BUILD_DIR
set -u
build="$1"
src_dir="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
fail=0
pass=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" 2>&1 || { cat "$tmp/install.log"; bad install; }
for f in bin/sabodem include/sabodem.h include/sabodem_run.h lib/pkgconfig/sabodem.pc lib/cmake/sabodem/sabodemConfig.cmake \
         share/sabodem/plot_side.py share/man/man1/sabodem.1 share/bash-completion/completions/sabodem; do
  [ -f "$prefix/$f" ] || bad "not installed: $f"
done
so=$(cd "$prefix/lib" && ls libsabodem.so.* 2>/dev/null | head -1)
[ -n "$so" ] && [ -L "$prefix/lib/libsabodem.so" ] && ok || bad "no libsabodem.so with its soname"
export LD_LIBRARY_PATH="$prefix/lib"

# pkg-config: compile and link a program of one's own, run it (a free fall for 0.01 s from z = 0.1 m;
# 0.1 - g t^2 / 2 = 0.0995095, and the leapfrog's thousand steps land on 0.099509)
want="sabodem $("$prefix/bin/sabodem" --version | cut -d' ' -f2): 1 body, z = 0.099509 m, t = 0.0100 s, exit 0"
flags=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs sabodem)
if cc -std=c11 -Wall -Werror "$src_dir/tests/install/use_sabodem.c" $flags -lm -o "$tmp/use_pc" 2>"$tmp/cc.log"; then
  got=$("$tmp/use_pc" "$tmp/out-pc")
  [ "$got" = "$want" ] && ok || bad "pkg-config program: '$got' (want '$want')"
else cat "$tmp/cc.log"; bad "pkg-config build"; fi

# the CMake package
if cmake -S "$src_dir/tests/install" -B "$tmp/cm" -DCMAKE_PREFIX_PATH="$prefix" >"$tmp/cm.log" 2>&1 &&
   cmake --build "$tmp/cm" >>"$tmp/cm.log" 2>&1; then
  got=$("$tmp/cm/use_sabodem" "$tmp/out-cm")
  [ "$got" = "$want" ] && ok || bad "CMake package program: '$got'"
else cat "$tmp/cm.log"; bad "CMake package build"; fi

# the installed program draws with the installed scripts (from any directory, no SABODEM_SCRIPTS)
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  (cd "$tmp" && env -u SABODEM_SCRIPTS "$prefix/bin/sabodem" run "$src_dir/examples/flume_small.yaml" -o "$tmp/flume" \
     --set output.png=true --set output.log_interval=0.5 --set phases.capture_limit=0.02 >"$tmp/run.log" 2>&1)
  [ -s "$tmp/flume/side_final.png" ] && ok || { cat "$tmp/run.log"; bad "installed program: no side_final.png"; }
fi

# the man page and the completion are the program's own
cmp -s <("$prefix/bin/sabodem" man) "$prefix/share/man/man1/sabodem.1" && ok || bad "installed man page differs"
cmp -s <("$prefix/bin/sabodem" completion bash) "$prefix/share/bash-completion/completions/sabodem" && ok ||
  bad "installed completion differs"

# the Python package under the prefix finds the library beside it (no SABODEM_LIBRARY)
pydir=$(ls -d "$prefix"/lib/python3*/dist-packages)
got=$(cd "$tmp" && env -u SABODEM_LIBRARY PYTHONPATH="$pydir" /usr/bin/python3 -c \
  "import sabodem, os; print(sabodem.version(), os.path.realpath(sabodem.library_path))")
[ "$got" = "$("$prefix/bin/sabodem" --version | cut -d' ' -f2) $(realpath "$prefix/lib/$so")" ] && ok ||
  bad "installed Python package: '$got'"

echo "install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
