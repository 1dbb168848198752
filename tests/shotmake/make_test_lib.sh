# Shared set-up of the make-pipeline tests (shot_make_test.sh, shot_reuse_test.sh), sourced by
# them. make_test_setup NAME DEFAULT_SHOT SOURCE_DIR BIN_DIR [SHOT_FILE] sets src, bin and
# shot_src (default: SOURCE_DIR/shots/DEFAULT_SHOT.json), checks jq and the stage binaries,
# detaches from the jobserver of a make that runs ctest (the tests set -j themselves), and makes
# the scratch folder $tmp, removed at exit unless the test failed or SHOT_MAKE_TEST_KEEP=1.

fail() { echo "FAIL: $*" >&2; exit 1; }

make_test_setup() {
    local name=$1 default_shot=$2
    shift 2
    [ $# -ge 2 ] || { echo "usage: $name.sh SOURCE_DIR BIN_DIR [SHOT_FILE]" >&2; exit 2; }
    src=$(cd "$1" && pwd)
    bin=$(cd "$2" && pwd)
    shot_src=${3:-$src/shots/$default_shot.json}
    command -v jq >/dev/null || fail "jq not found (apt-get install jq): pipeline/shot.mk needs it"
    local b
    for b in mc-shot mc-init mc-sim mc-surface mc-render; do
        [ -x "$bin/$b" ] || fail "$bin/$b: not built"
    done
    unset MAKEFLAGS MFLAGS MAKELEVEL MAKEOVERRIDES
    tmp=$(mktemp -d "${TMPDIR:-/tmp}/mudcrack-$name.XXXXXX")
    make_test_name=$name
    trap make_test_cleanup EXIT
}

make_test_cleanup() {
    local rc=$?
    if [ "${SHOT_MAKE_TEST_KEEP:-0}" = 1 ] || [ $rc -ne 0 ]; then
        echo "$make_test_name: kept $tmp"
    else
        rm -rf "$tmp"
    fi
}
