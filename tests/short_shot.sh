# The shortened copy of a shot the long pipeline tests run (tests/farm/farm_test.sh,
# tests/shotmake/shot_make_test.sh), sourced by them so they run the same cut:
#
#   short_shot SHOT_FILE > COPY
#
# SHOT_FILE without its comment lines (jq reads plain JSON), cut to its first 24 frames with a
# 6-view turntable: three frame chunks of 8 for the surfacing and the render, and a sim checkpoint
# (every 10 frames by default) before the last frame, so every farm and make step runs; a longer
# shot or turntable adds cost and no coverage (the whole 40-frame demo took 654 s of a 42-minute
# CI in the farm test). A box source keeps the middle half of its width and depth (x and z, about
# the box's centre; its height and spacing as given): a quarter of the particles, and still cracks
# in every chunk (fig8_c's 0.6 m square: 8,125 particles, the first broken edges at frame 6 and
# 1,147 by frame 24; in a ctest on a Zen 5, 2026-12-02, the farm test took 84 s and the make test
# 52 s on it, 171 and 98 s on the whole 1.2 m slab). The Blender test runs the whole slab: its
# `ours` variant must show many piece ids, and the cut's has one by frame 20. Fails when jq cannot
# read the shot.
short_shot() {
    sed '/^[[:space:]]*\/\//d' "$1" | jq '
        .frames.end = ([.frames.end, 24] | min) | .render.turntable.views = 6
        | if .source.type == "box" then
              .source.box |= (.min as $lo | .max as $hi | reduce (0, 2) as $axis (.;
                  (($lo[$axis] + $hi[$axis]) / 2) as $mid | (($hi[$axis] - $lo[$axis]) / 4) as $quarter
                  | .min[$axis] = $mid - $quarter | .max[$axis] = $mid + $quarter))
          else . end'
}
