#pragma once
/// Headless preview renderer: OpenGL 3.3 core through OSMesa (llvmpipe), no display needed.
/// A studio look an FX supervisor can review: key/fill/rim lights, a ground plane at the lowest
/// point of the stage with a soft (PCF) shadow of the key light, MSAA, filmic tone mapping,
/// a soft gradient background. Returns pixels; file I/O belongs to pipeline/io.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/render_params.h"
#include "render/scene.h"

namespace mudcrack {

/// An 8-bit RGBA image, row-major, top row first, with the object coverage of each pixel.
struct RenderedImage {
    int width = 0, height = 0;
    std::vector<uint8_t> rgba;      // (width * height * 4), alpha is 255
    std::vector<uint8_t> coverage;  // (width * height): 255 where meshes/particles cover the
                                    // pixel fully, 0 on background and ground (MSAA-averaged)
};

/// Fraction of the image covered by the scene's objects, in [0, 1].
double coverage_fraction(const RenderedImage& image);

/// Settings that come from outside RenderParams.
struct ShadingOptions {
    float alpha0 = 0;        // center of the hardening colormap (the shot's /plasticity/alpha0)
    bool is_unlit = false;   // output the base color only (no lights, shadow or tone mapping),
                             // sRGB-encoded: checks the color modes pixel-exactly
    bool has_ground = true;  // draw the ground plane and its shadow
};

class Renderer {
public:
    /// Creates the OSMesa GL 3.3 core context and the framebuffers. Throws InputError for a
    /// sample count below 1 or an alpha_range <= 0, RuntimeError if OSMesa or GL setup fails.
    /// @note A side outside [kMinResolution, kMaxResolution] is a bug, stopped by a precondition
    /// check: the shot spec refuses such a /render/resolution, naming the file and key.
    /// llvmpipe's thread count is fixed by LP_NUM_THREADS when the first context is made.
    explicit Renderer(const RenderParams& params, const ShadingOptions& options = {});
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Uploads a scene (replacing the previous one). `stage` fixes the ground height (its
    /// lowest y), the ground size and the shadow frustum; pass the bounds of all frames of an
    /// animation so they stay put; empty: the scene's own bounds.
    /// Throws InputError if a mesh's attribute arrays do not match its vertex count or a face
    /// indexes a missing vertex.
    void set_scene(const Scene& scene, const Bounds& stage = {});

    /// Renders the uploaded scene through `camera`.
    RenderedImage render(const Camera& camera);

    /// The MSAA sample count in use (params.samples clamped to what the GL supports; 1 = off).
    int samples() const;
    /// "llvmpipe (LLVM 15.0.6, 256 bits)" etc.
    std::string gl_renderer() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace mudcrack
