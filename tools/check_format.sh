#!/usr/bin/env bash
# Checks that every C++ source and test is as clang-format makes it under the repository's
# .clang-format (docs/style.md): prints each difference and fails on any. Run by ctest (test
# `format`) and by `make format-check`; `make format` applies the format in place.
#
#   tools/check_format.sh [SOURCE_DIR]           check the tree
#   tools/check_format.sh --fix [SOURCE_DIR]     format the tree in place
#   tools/check_format.sh --files FILE...        check just these files
#
# The tree is every .h and .cpp under the source folders, found on disk (so an export without
# git history is checked the same way); tests/data holds inputs, not sources, and is skipped.
set -euo pipefail
command -v clang-format >/dev/null ||
    { echo "check_format.sh: clang-format not found (make test-deps installs it)" >&2; exit 1; }

mode=check
if [[ ${1:-} == --fix ]]; then mode=fix; shift; fi
if [[ ${1:-} == --files ]]; then
    shift
    files=("$@")
else
    root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
    [[ -f $root/.clang-format ]] || { echo "check_format.sh: $root/.clang-format not found" >&2; exit 1; }
    mapfile -t files < <(cd "$root" && find sim surfacing render pipeline tools tests \
        -path tests/data -prune -o \( -name '*.h' -o -name '*.cpp' \) -print | sort | sed "s|^|$root/|")
fi
[[ ${#files[@]} -gt 0 ]] || { echo "check_format.sh: no files to check" >&2; exit 1; }

if [[ $mode == fix ]]; then
    clang-format -i "${files[@]}"
    echo "check_format.sh: formatted ${#files[@]} files ($(clang-format --version))"
    exit 0
fi
if ! clang-format --dry-run --Werror "${files[@]}"; then
    echo "check_format.sh: files differ from .clang-format ($(clang-format --version)); run make format" >&2
    exit 1
fi
echo "check_format.sh: ${#files[@]} files as .clang-format makes them"
