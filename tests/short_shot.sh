# The shortened copy of a shot the long pipeline tests run (tests/farm/farm_test.sh,
# tests/shotmake/shot_make_test.sh), sourced by them so they run the same cut:
#
#   short_shot SHOT_FILE > COPY
#
# SHOT_FILE without its comment lines (jq reads plain JSON), cut to its first 24 frames with a
# 6-view turntable: three frame chunks of 8 for the surfacing and the render, and a sim checkpoint
# (every 10 frames by default) before the last frame, so every farm and make step runs; a longer
# shot or turntable adds cost and no coverage (the whole 40-frame demo took 654 s of a 42-minute
# CI in the farm test). Fails when jq cannot read the shot.
short_shot() {
    sed '/^[[:space:]]*\/\//d' "$1" | jq '.frames.end = ([.frames.end, 24] | min) | .render.turntable.views = 6'
}
