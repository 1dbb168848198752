#!/usr/bin/env bash
# Checks that includes and links point down only (docs/architecture.md §2), and optionally that no
# stage program but mc-render links OSMesa. Run by ctest (tests `layering` and
# `layering_programs`).
#
#   tools/check_layering.sh [SOURCE_DIR] [--bin BIN_DIR]
#
# Every product folder has a rank below; a file may include a header of its own folder or of a
# folder of lower rank, and a library may link its own folder's libraries or those of a lower
# rank. Folders of equal rank are independent (surfacing and render; the stage libraries). A
# folder without a rank is an error: give a new folder its place here and in architecture.md §2.
# tests/ sit on top and are not checked.
set -euo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
shift || true
bin=""
if [[ ${1:-} == --bin ]]; then bin=${2:?--bin needs a folder}; fi
cd "$root"

# folder ranks, low to high; shared by the include and the link checks
ranks='
sim/core 0
sim 1
sim/material 2
sim/grid 2
sim/moisture 3
sim/mpm 4
surfacing 5
render 5
pipeline/io 6
pipeline/init 7
pipeline/measure 7
pipeline/shot 8
pipeline/stages 9
pipeline/stages/init 10
pipeline/stages/sim 10
pipeline/stages/surface 10
pipeline/stages/render 10
pipeline/stages/measure 10
pipeline/stages/shot 10
pipeline/cmd 11
tools 12
tools/report 12
tools/blender 12
'
# the folder of each mudcrack:: library (its name without mudcrack_ / mudcrack::)
targets='
core sim/core
sim sim/mpm
surfacing surfacing
renderparams render
render render
io pipeline/io
init pipeline/init
measure pipeline/measure
shot pipeline/shot
stageoptions pipeline/stages
initstage pipeline/stages/init
simstage pipeline/stages/sim
surfacestage pipeline/stages/surface
renderstage pipeline/stages/render
measurestage pipeline/stages/measure
shottool pipeline/stages/shot
cli pipeline/cmd
'

# "file:line:#include "a/b/c.h"" for every product source
includes=$(grep -rnE '^\s*#\s*include\s+"[^"]+/[^"]+"' --include='*.h' --include='*.cpp' \
    sim surfacing render pipeline tools || true)
# "CMakeLists.txt:target dep dep ..." for every target_link_libraries of a mudcrack_ target
links=$(find sim surfacing render pipeline tools -name CMakeLists.txt -print0 |
    xargs -0 awk '
        /target_link_libraries\(/ { collecting = 1; text = "" }
        collecting { text = text " " $0 }
        collecting && /\)/ { collecting = 0; print FILENAME ":" text }')

status=0
awk -v ranks="$ranks" -v targets="$targets" -v includes="$includes" -v links="$links" '
function folder_of(path,    n, p, q, out) { n = split(path, p, "/"); out = p[1]; for (q = 2; q < n; ++q) out = out "/" p[q]; return out }
function fail(msg) { print "layering: " msg; bad = 1 }
BEGIN {
    n = split(ranks, lines, "\n")
    for (i = 1; i <= n; ++i) if (split(lines[i], f, " ") == 2) rank[f[1]] = f[2]
    n = split(targets, lines, "\n")
    for (i = 1; i <= n; ++i) if (split(lines[i], f, " ") == 2) home[f[1]] = f[2]
    # includes
    n = split(includes, lines, "\n")
    for (i = 1; i <= n; ++i) {
        if (lines[i] == "") continue
        split(lines[i], parts, ":")
        file = parts[1]; where = parts[1] ":" parts[2]
        match(lines[i], /"[^"]+"/); header = substr(lines[i], RSTART + 1, RLENGTH - 2)
        from = folder_of(file); to = folder_of(header)
        if (!(from in rank)) { fail(where ": folder " from " has no rank (tools/check_layering.sh)"); continue }
        if (!(to in rank)) { fail(where ": includes " header ", whose folder " to " has no rank"); continue }
        if (from != to && rank[to] >= rank[from])
            fail(where ": " from " (rank " rank[from] ") includes " header " of " to " (rank " rank[to] ")")
    }
    # links
    n = split(links, lines, "\n")
    for (i = 1; i <= n; ++i) {
        if (lines[i] == "") continue
        file = substr(lines[i], 1, index(lines[i], ":") - 1)
        text = substr(lines[i], index(lines[i], ":") + 1)
        gsub(/[()]/, " ", text)
        m = split(text, tok, /[ \t]+/)
        target = ""
        for (j = 1; j <= m; ++j) if (tok[j] != "" && tok[j] != "target_link_libraries") { target = tok[j]; break }
        sub(/^mudcrack_/, "", target)
        if (!(target in home)) continue  # programs, tests and tools sit on top
        for (k = j + 1; k <= m; ++k) {
            dep = tok[k]
            if (dep !~ /^mudcrack(::|_)/ || dep == "mudcrack_warnings") continue
            sub(/^mudcrack(::|_)/, "", dep)
            if (!(dep in home)) { fail(file ": " target " links mudcrack::" dep ", which has no folder here"); continue }
            from = home[target]; to = home[dep]
            if (from != to && rank[to] >= rank[from])
                fail(file ": mudcrack::" target " (" from ") links mudcrack::" dep " (" to ")")
        }
    }
    exit bad
}' || status=1

# only mc-render draws: no other stage program may load OSMesa
if [[ -n $bin ]]; then
    for program in "$bin"/mc-*; do
        [[ -x $program && $(basename "$program") != mc-render ]] || continue
        if ldd "$program" | grep -qi osmesa; then
            echo "layering: $program links OSMesa (only mc-render may)"; status=1
        fi
    done
fi
[[ $status == 0 ]] && echo "layering: includes and links point down"
exit $status
