# cli_harness.sh: sourced by the bad-input case scripts (cli_cases.sh,
# triangulate_cases.sh) after they set tessera, fixtures and case. Makes the
# fixtures in a fresh $dir and defines fail and expect_error.
dir=$(mktemp -d "${TMPDIR:-/tmp}/tsr-cli-XXXXXX")
cap=$(mktemp -d "${TMPDIR:-/tmp}/tsr-cli-out-XXXXXX")
trap 'chmod -R u+w "$dir" 2>/dev/null; rm -rf "$dir" "$cap"' EXIT
"$fixtures" "$dir" || { echo "fixtures failed"; exit 1; }

fail() { echo "FAIL [$case]: $*"; exit 1; }

# expect_error WANT_EXIT PATTERN -- command...: runs the command, checks the
# exit code, one stderr line matching PATTERN, nothing on stdout, and no
# stray output files.
expect_error() {
  local want=$1 pattern=$2
  shift 3
  local before after
  before=$(ls -A "$dir" | sort)
  "$@" >"$cap/stdout" 2>"$cap/stderr"
  local rc=$?
  after=$(ls -A "$dir" | sort)
  local err
  err=$(cat "$cap/stderr")
  [ "$rc" -eq "$want" ] || fail "exit $rc, wanted $want; stderr: $err"
  [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] || fail "stderr is not one line: $err"
  printf '%s\n' "$err" | grep -qE -- "$pattern" || fail "stderr '$err' does not match '$pattern'"
  [ ! -s "$cap/stdout" ] || fail "output on stdout: $(head -c 300 "$cap/stdout")"
  [ "$before" = "$after" ] || fail "files changed: before [$before] after [$after]"
  echo "ok [$case]: $err"
}
