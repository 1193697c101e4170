# Shared by the command-line tests (sourced, not a test itself): the idrig binary from $1, a
# scratch directory removed on exit, and the two checks every script uses.
set -uo pipefail
idrig=$1
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
status=0
fail() { echo "FAIL: $*"; status=1; }
expect() {  # expect "fragment" command...: exit status 2 and a message naming the problem
  local fragment=$1; shift
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ $rc -ne 2 ] || ! grep -qF -- "$fragment" <<<"$out"; then
    fail "($rc): $* -> $out (expected '$fragment')"
  else
    echo "ok: $fragment"
  fi
}
