#!/usr/bin/env bash
# The tests that depend most on the rasteriser, run again under Mesa's second software
# rasteriser, softpipe (GL 3.3 core with EXT_depth_bounds_test, 3-6 times slower than
# llvmpipe): context paths, fallbacks, the depth-bounds test where it runs, the fixed-function
# pipeline, EGL against OSMesa and the window, the README's figures, and the built-in scene's
# shadow volumes and maps (with the texgen precision case on oa_dm3), maps drawn per light within
# the map budget, and the decisions the lit pass records against the masks drawn again (the
# paper's frame, subdivision, the G-buffer read where the sample picks). .ci/run runs it after the
# README's test command; docs/drivers.md says what differs between the drivers.
#
#   scripts/test-softpipe.sh            (after a release build of the tests, or it builds them)
set -euo pipefail
cd "$(dirname "$0")/.."
export GALLIUM_DRIVER=softpipe

cargo build --release --quiet
renderer=$("${CARGO_TARGET_DIR:-target}/release/shadowlab" info | sed -n 's/^renderer: *//p')
if [ "$renderer" != "softpipe" ]; then
    echo "error: GALLIUM_DRIVER=softpipe gave renderer '$renderer', not softpipe (Debian: libgl1-mesa-dri)" >&2
    exit 1
fi

total=$(date +%s)
run() {
    local start
    start=$(date +%s)
    echo "== softpipe: cargo test --release --test $*"
    cargo test --release --quiet --test "$@"
    echo "== ($(( $(date +%s) - start )) s)"
}
run contexts
run fallbacks
run depth_bounds
run fixed_function
run foundation
run cli
run shadow_volume
run shadow_map -- copy_and_fbo hardware_and_shader alpha_and_intensity light_relative_texgen light_relative_depth lifted
# Maps drawn per light against every map first, and a released renderer: what a rasteriser
# could draw differently. The other cases count textures reused and renderers grouped (the
# same on every driver) and take minutes here.
run map_budget -- maps_drawn_per_light_within_the_budget a_renderer_released_between_configurations
# The decisions the lit pass records: the five scenes' and the hard cases' take minutes here.
run recorded_masks -- shader_decides the_g_buffer
echo "== softpipe pass: $(( $(date +%s) - total )) s"
