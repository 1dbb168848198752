// mc-render's job, without the CLI: the surface manifest's per-frame entries are read once for
// the frames without a crack file and for the bounds that frame the shot.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "pipeline/stages/render/render_job.h"

namespace mudcrack {
namespace {

using nlohmann::json;

json entry(int frame, json bounds, bool has_crack_file = true) {
    json e = {{"frame", frame},
              {"crack", {{"file", has_crack_file ? json("crack.glb") : json(nullptr)}}}};
    if (!bounds.is_discarded()) e["bounds"] = std::move(bounds);
    return e;
}

json box(float lo, float hi) { return {{"min", {lo, lo, lo}}, {"max", {hi, hi, hi}}}; }

TEST(RenderJob, SurfaceFramesAreIndexedOnce) {
    const json manifest = {{"per_frame",
                            {entry(1, box(0, 1)),
                             entry(2, nullptr, false),
                             "not an object",
                             {{"frame", "3"}},
                             entry(3, box(-2, 0.5f))}}};
    const SurfaceFrameIndex index = index_surface_frames(manifest);
    EXPECT_EQ(index.frames_without_cracks, (std::set<int>{2}));
    ASSERT_EQ(index.bounds.size(), 3u);
    EXPECT_TRUE(index.bounds.at(2).is_null());

    const std::optional<Bounds> b = manifest_bounds(index, 1, 3, "surface/manifest.json");
    ASSERT_TRUE(b.has_value());
    EXPECT_EQ(b->min, Vec3f::Constant(-2));
    EXPECT_EQ(b->max, Vec3f::Constant(1));
    // frames 2 alone: null bounds, nothing to frame
    EXPECT_TRUE(manifest_bounds(index, 2, 2, "m")->is_empty());
    EXPECT_TRUE(index_surface_frames(json::object()).bounds.empty());
}

TEST(RenderJob, MissingOrMalformedBoundsFallBackToTheMeshes) {
    // a frame without bounds (an older mc-surface) or with malformed ones: read the meshes instead
    const json no_bounds = {
        {"per_frame", {entry(1, box(0, 1)), entry(2, json(json::value_t::discarded))}}};
    EXPECT_FALSE(manifest_bounds(index_surface_frames(no_bounds), 1, 2, "m").has_value());
    EXPECT_TRUE(manifest_bounds(index_surface_frames(no_bounds), 1, 1, "m").has_value());
    const json bad = {{"per_frame", {entry(1, {{"min", {0, 0}}, {"max", {1, 1, 1}}})}}};
    EXPECT_FALSE(manifest_bounds(index_surface_frames(bad), 1, 1, "m").has_value());
    // a frame beyond the manifest's entries
    EXPECT_FALSE(manifest_bounds(index_surface_frames(no_bounds), 1, 5, "m").has_value());
}

}  // namespace
}  // namespace mudcrack
