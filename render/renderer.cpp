#include "render/renderer.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "render/colormap.h"
#include "render/shaders.h"
#include "sim/core/check.h"
#include "sim/core/error.h"

namespace mudcrack {

double coverage_fraction(const RenderedImage& image) {
    if (image.coverage.empty()) return 0;
    double sum = 0;
    for (uint8_t c : image.coverage) sum += c;
    return sum / (255.0 * double(image.coverage.size()));
}

namespace {

constexpr int kShadowMapSize = 2048;

// light rig (linear RGB intensities), tuned for a mid-grey soil albedo under the ACES curve
constexpr float kKeyColor[3] = {1.55f, 1.45f, 1.32f};
constexpr float kFillColor[3] = {0.26f, 0.30f, 0.38f};
constexpr float kRimColor[3] = {1.10f, 1.10f, 1.15f};
constexpr float kSkyColor[3] = {0.26f, 0.29f, 0.34f};
constexpr float kBounceColor[3] = {0.10f, 0.09f, 0.08f};
constexpr float kCrackTint[3] = {0.62f, 0.50f, 0.42f};         // darker, warmer interior soil
constexpr float kGroundColor[3] = {0.16f, 0.16f, 0.16f};       // neutral grey, linear
constexpr float kBackgroundTop[3] = {0.40f, 0.43f, 0.47f};     // display space
constexpr float kBackgroundBottom[3] = {0.15f, 0.16f, 0.17f};  // display space
constexpr float kExposure = 0.6f;
constexpr float kShadowRadiusTexels = 3.5f;

void check_gl(const char* what) {
    const GLenum e = glGetError();
    if (e != GL_NO_ERROR)
        throw RuntimeError(std::string("render: OpenGL error 0x") + [&] {
            char b[16];
            std::snprintf(b, sizeof b, "%04x", unsigned(e));
            return std::string(b);
        }() + " during " + what);
}

/// What GL says about a shader or program that failed (get_log: glGetShaderInfoLog or
/// glGetProgramInfoLog).
template <class GetLog>
std::string info_log(GLuint id, GetLog get_log) {
    char log[4096] = {0};
    get_log(id, sizeof log, nullptr, log);
    return log;
}

GLuint compile(GLenum type, const std::string& source, const char* name) {
    const GLuint s = glCreateShader(type);
    const char* text = source.c_str();
    glShaderSource(s, 1, &text, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = info_log(s, glGetShaderInfoLog);
        glDeleteShader(s);
        throw RuntimeError(std::string("render: shader ") + name + " does not compile: " + log);
    }
    return s;
}

/// A linked GL program with cached uniform locations.
struct Program {
    GLuint id = 0;
    std::unordered_map<std::string, GLint> locations;

    void build(const char* name, const char* vertex, const char* fragment, bool needs_shading) {
        const std::string head = "#version 330 core\n" + color_mode_glsl_defines();
        const std::string chunk = needs_shading ? shaders::kShadingChunk : "";
        const GLuint vs = compile(GL_VERTEX_SHADER, head + vertex, name);
        const GLuint fs = compile(GL_FRAGMENT_SHADER, head + chunk + fragment, name);
        id = glCreateProgram();
        glAttachShader(id, vs);
        glAttachShader(id, fs);
        glLinkProgram(id);
        glDeleteShader(vs);
        glDeleteShader(fs);
        GLint ok = 0;
        glGetProgramiv(id, GL_LINK_STATUS, &ok);
        if (!ok)
            throw RuntimeError(std::string("render: program ") + name +
                               " does not link: " + info_log(id, glGetProgramInfoLog));
    }
    GLint loc(const char* name) {
        auto it = locations.find(name);
        if (it != locations.end()) return it->second;
        return locations[name] = glGetUniformLocation(id, name);
    }
    void set(const char* n, int v) { glUniform1i(loc(n), v); }
    void set(const char* n, float v) { glUniform1f(loc(n), v); }
    void set(const char* n, const Vec3f& v) { glUniform3f(loc(n), v.x(), v.y(), v.z()); }
    void set(const char* n, const float (&v)[3]) { glUniform3f(loc(n), v[0], v[1], v[2]); }
    void set(const char* n, float a, float b) { glUniform2f(loc(n), a, b); }
    void set(const char* n, const Eigen::Matrix4f& m) {
        glUniformMatrix4fv(loc(n), 1, GL_FALSE, m.data());
    }
};

/// One uploaded mesh.
struct GpuMesh {
    GLuint vao = 0, vbo[4] = {0, 0, 0, 0}, ebo = 0;
    GLsizei index_count = 0;
    bool has_saturation = false, has_alpha = false;
    SurfaceKind kind = SurfaceKind::Boundary;
};

/// Area-weighted vertex normals (the cross product's length is twice the face area).
std::vector<Vec3f> vertex_normals(const TriMesh& m) {
    std::vector<Vec3f> n(m.positions.size(), Vec3f::Zero());
    for (const Tri& f : m.faces) {
        const Vec3f fn =
            (m.positions[f[1]] - m.positions[f[0]]).cross(m.positions[f[2]] - m.positions[f[0]]);
        for (int k = 0; k < 3; ++k) n[f[k]] += fn;
    }
    for (Vec3f& v : n) {
        const float len = v.norm();
        v = len > 0 ? Vec3f(v / len) : Vec3f(0, 1, 0);
    }
    return n;
}

void validate_mesh(const TriMesh& m, size_t index) {
    const size_t nv = m.positions.size();
    auto where = [&] {
        return "render: scene mesh " + std::to_string(index) + " (\"" + m.name + "\")";
    };
    auto check_size = [&](size_t n, const char* what) {
        if (n != 0 && n != nv)
            throw InputError(where() + ": " + what + " has " + std::to_string(n) +
                             " entries, expected 0 or the vertex count " + std::to_string(nv));
    };
    check_size(m.normals.size(), "normals");
    check_size(m.saturation.size(), "saturation");
    check_size(m.alpha.size(), "alpha");
    for (size_t f = 0; f < m.faces.size(); ++f)
        for (int k = 0; k < 3; ++k)
            if (m.faces[f][k] < 0 || size_t(m.faces[f][k]) >= nv)
                throw InputError(where() + ": face " + std::to_string(f) + " has vertex index " +
                                 std::to_string(m.faces[f][k]) + ", expected 0.." +
                                 std::to_string(nv == 0 ? 0 : nv - 1));
}

template <class T>
void upload_buffer(GLuint vbo, const std::vector<T>& data, GLenum target = GL_ARRAY_BUFFER) {
    glBindBuffer(target, vbo);
    glBufferData(target, GLsizeiptr(data.size() * sizeof(T)), data.data(), GL_STATIC_DRAW);
}

}  // namespace

struct Renderer::Impl {
    RenderParams params;
    ShadingOptions options;
    OSMesaContext context = nullptr;
    std::vector<uint8_t> dummy_buffer;  // OSMesa needs a bound buffer; we draw into FBOs
    int samples = 1;
    std::string renderer_name;

    Program background, mesh, mesh_shadow, sprite, sprite_shadow, ground;
    GLuint empty_vao = 0;
    GLuint msaa_fbo = 0, msaa_color = 0, msaa_coverage = 0, msaa_depth = 0;
    GLuint resolve_fbo = 0, resolve_color = 0, resolve_coverage = 0;
    GLuint shadow_fbo = 0, shadow_tex = 0;

    std::vector<GpuMesh> meshes;
    GLuint sprite_vao = 0, sprite_vbo[3] = {0, 0, 0};
    size_t sprite_count = 0;
    bool sprite_has_saturation = false, sprite_has_alpha = false;
    float sprite_radius = 0;
    Bounds stage;

    void make_current() {
        if (!OSMesaMakeCurrent(context, dummy_buffer.data(), GL_UNSIGNED_BYTE, 16, 16))
            throw RuntimeError("render: OSMesaMakeCurrent failed");
    }
    void create_context();
    void create_framebuffers();
    void release_scene();
    void draw_shadow_pass(const Eigen::Matrix4f& light_view, const Eigen::Matrix4f& light_proj);
    void set_shading_uniforms(Program& p, const Camera& camera,
                              const Eigen::Matrix4f& light_view_proj, const Vec3f& key,
                              const Vec3f& fill, const Vec3f& rim);
    /// The particles as sphere impostors (when there are any).
    void draw_sprites(const Camera& camera, const Eigen::Matrix4f& view,
                      const Eigen::Matrix4f& proj, const Eigen::Matrix4f& light_view_proj,
                      const Vec3f& key, const Vec3f& fill, const Vec3f& rim);
    /// The ground plane under the stage, blended into the background.
    void draw_ground(const Camera& camera, const Eigen::Matrix4f& view_proj,
                     const Eigen::Matrix4f& light_view_proj, const Vec3f& key, const Vec3f& fill,
                     const Vec3f& rim, const Vec3f& center, float radius, float ground_radius);
    /// Resolves the multisampled buffers and reads the image back, top row first.
    RenderedImage read_back(int w, int h);
};

void Renderer::Impl::create_context() {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           24,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           3,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           3,
                           0};
    context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!context) throw RuntimeError("render: OSMesaCreateContextAttribs (GL 3.3 core) failed");
    dummy_buffer.assign(16 * 16 * 4, 0);
    make_current();
    const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    renderer_name = name ? name : "?";
}

void Renderer::Impl::create_framebuffers() {
    const int w = params.width, h = params.height;
    GLint max_samples = 1;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    samples = std::max(1, std::min(params.samples, int(max_samples)));
    const GLsizei ms = samples > 1 ? samples : 0;

    // multisampled scene target: color, coverage mask, depth
    glGenRenderbuffers(1, &msaa_color);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, ms, GL_RGBA8, w, h);
    glGenRenderbuffers(1, &msaa_coverage);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_coverage);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, ms, GL_R8, w, h);
    glGenRenderbuffers(1, &msaa_depth);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, ms, GL_DEPTH_COMPONENT24, w, h);
    glGenFramebuffers(1, &msaa_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, msaa_coverage);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
    const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, both);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw RuntimeError("render: the multisampled framebuffer is incomplete (" +
                           std::to_string(w) + "x" + std::to_string(h) + ", " +
                           std::to_string(samples) + " samples)");

    // single-sample resolve target
    glGenRenderbuffers(1, &resolve_color);
    glBindRenderbuffer(GL_RENDERBUFFER, resolve_color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glGenRenderbuffers(1, &resolve_coverage);
    glBindRenderbuffer(GL_RENDERBUFFER, resolve_coverage);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_R8, w, h);
    glGenFramebuffers(1, &resolve_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER,
                              resolve_coverage);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw RuntimeError("render: the resolve framebuffer is incomplete");

    // key light shadow map; outside it everything is lit
    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D, shadow_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowMapSize, kShadowMapSize, 0,
                 GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    const float border[4] = {1, 1, 1, 1};
    glTexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, border);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw RuntimeError("render: the shadow framebuffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("framebuffer setup");
}

void Renderer::Impl::release_scene() {
    for (GpuMesh& m : meshes) {
        glDeleteVertexArrays(1, &m.vao);
        glDeleteBuffers(4, m.vbo);
        glDeleteBuffers(1, &m.ebo);
    }
    meshes.clear();
    if (sprite_vao) {
        glDeleteVertexArrays(1, &sprite_vao);
        glDeleteBuffers(3, sprite_vbo);
        sprite_vao = 0;
    }
    sprite_count = 0;
}

Renderer::Renderer(const RenderParams& params, const ShadingOptions& options)
    : m_impl(std::make_unique<Impl>()) {
    Impl& r = *m_impl;
    // the shot layer bounds /render/resolution (naming the file); here a bad size is a bug
    MC_CHECK_GE(params.width, kMinResolution);
    MC_CHECK_GE(params.height, kMinResolution);
    MC_CHECK_LE(params.width, kMaxResolution);
    MC_CHECK_LE(params.height, kMaxResolution);
    if (params.samples < 1)
        throw InputError("render: samples = " + std::to_string(params.samples) + ": expected >= 1");
    if (!(params.alpha_range > 0))
        throw InputError("render: alpha_range = " + std::to_string(params.alpha_range) +
                         ": expected > 0");
    r.params = params;
    r.options = options;
    r.create_context();
    r.background.build("background", shaders::kBackgroundVertex, shaders::kBackgroundFragment,
                       false);
    r.mesh.build("mesh", shaders::kMeshVertex, shaders::kMeshFragment, true);
    r.mesh_shadow.build("mesh_shadow", shaders::kMeshShadowVertex, shaders::kDepthOnlyFragment,
                        false);
    r.sprite.build("sprite", shaders::kSpriteVertex, shaders::kSpriteFragment, true);
    r.sprite_shadow.build("sprite_shadow", shaders::kSpriteShadowVertex,
                          shaders::kSpriteShadowFragment, false);
    r.ground.build("ground", shaders::kGroundVertex, shaders::kGroundFragment, true);
    glGenVertexArrays(1, &r.empty_vao);
    r.create_framebuffers();
}

Renderer::~Renderer() {
    Impl& r = *m_impl;
    if (!r.context) return;
    // GL objects die with the context
    OSMesaDestroyContext(r.context);
}

int Renderer::samples() const { return m_impl->samples; }
std::string Renderer::gl_renderer() const { return m_impl->renderer_name; }

void Renderer::set_scene(const Scene& scene, const Bounds& stage) {
    Impl& r = *m_impl;
    for (size_t i = 0; i < scene.meshes.size(); ++i) validate_mesh(scene.meshes[i].mesh, i);
    const ParticleSprites& ps = scene.particles;
    if ((!ps.saturation.empty() && ps.saturation.size() != ps.size()) ||
        (!ps.alpha.empty() && ps.alpha.size() != ps.size()))
        throw InputError("render: particles: saturation/alpha have " +
                         std::to_string(ps.saturation.size()) + "/" +
                         std::to_string(ps.alpha.size()) + " entries, expected 0 or " +
                         std::to_string(ps.size()));
    if (ps.size() > 0 && !(ps.radius > 0))
        throw InputError("render: particles: radius = " + std::to_string(ps.radius) +
                         ": expected > 0");
    r.make_current();
    r.release_scene();
    r.stage = stage.is_empty() ? scene_bounds(scene) : stage;

    for (const SceneMesh& sm : scene.meshes) {
        const TriMesh& m = sm.mesh;
        if (m.faces.empty()) continue;
        GpuMesh g;
        g.kind = sm.kind;
        g.index_count = GLsizei(m.faces.size() * 3);
        g.has_saturation = !m.saturation.empty();
        g.has_alpha = !m.alpha.empty();
        glGenVertexArrays(1, &g.vao);
        glBindVertexArray(g.vao);
        glGenBuffers(4, g.vbo);
        glGenBuffers(1, &g.ebo);
        upload_buffer(g.vbo[0], m.positions);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
        glEnableVertexAttribArray(0);
        upload_buffer(g.vbo[1], m.normals.empty() ? vertex_normals(m) : m.normals);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
        glEnableVertexAttribArray(1);
        if (g.has_saturation) {
            upload_buffer(g.vbo[2], m.saturation);
            glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
            glEnableVertexAttribArray(2);
        }
        if (g.has_alpha) {
            upload_buffer(g.vbo[3], m.alpha);
            glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
            glEnableVertexAttribArray(3);
        }
        upload_buffer(g.ebo, m.faces, GL_ELEMENT_ARRAY_BUFFER);  // Tri is 3 packed int32
        r.meshes.push_back(g);
    }

    if (ps.size() > 0) {
        r.sprite_count = ps.size();
        r.sprite_radius = ps.radius;
        r.sprite_has_saturation = !ps.saturation.empty();
        r.sprite_has_alpha = !ps.alpha.empty();
        glGenVertexArrays(1, &r.sprite_vao);
        glBindVertexArray(r.sprite_vao);
        glGenBuffers(3, r.sprite_vbo);
        upload_buffer(r.sprite_vbo[0], ps.positions);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
        glEnableVertexAttribArray(0);
        glVertexAttribDivisor(0, 1);
        if (r.sprite_has_saturation) {
            upload_buffer(r.sprite_vbo[1], ps.saturation);
            glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
            glEnableVertexAttribArray(1);
            glVertexAttribDivisor(1, 1);
        }
        if (r.sprite_has_alpha) {
            upload_buffer(r.sprite_vbo[2], ps.alpha);
            glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
            glEnableVertexAttribArray(2);
            glVertexAttribDivisor(2, 1);
        }
    }
    glBindVertexArray(0);
    check_gl("scene upload");
}

void Renderer::Impl::draw_shadow_pass(const Eigen::Matrix4f& light_view,
                                      const Eigen::Matrix4f& light_proj) {
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glViewport(0, 0, kShadowMapSize, kShadowMapSize);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glClear(GL_DEPTH_BUFFER_BIT);
    // slope-scaled bias against acne; the lookup adds a normal offset as well
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 4.0f);
    const Eigen::Matrix4f light_view_proj = light_proj * light_view;
    glUseProgram(mesh_shadow.id);
    mesh_shadow.set("u_light_view_proj", light_view_proj);
    for (const GpuMesh& g : meshes) {
        glBindVertexArray(g.vao);
        glDrawElements(GL_TRIANGLES, g.index_count, GL_UNSIGNED_INT, nullptr);
    }
    if (sprite_count > 0) {
        glUseProgram(sprite_shadow.id);
        sprite_shadow.set("u_light_view", light_view);
        sprite_shadow.set("u_light_proj", light_proj);
        sprite_shadow.set("u_radius", sprite_radius);
        glBindVertexArray(sprite_vao);
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(sprite_count));
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
}

void Renderer::Impl::set_shading_uniforms(Program& p, const Camera& camera,
                                          const Eigen::Matrix4f& light_view_proj, const Vec3f& key,
                                          const Vec3f& fill, const Vec3f& rim) {
    p.set("u_mode", static_cast<int>(params.color_mode));  // the shaders' MC_COLOR_MODE_*
    p.set("u_albedo", params.albedo.cast<float>().eval());
    p.set("u_moisture_darkening", kMoistureDarkening);
    p.set("u_alpha0", options.alpha0);
    p.set("u_alpha_range", float(params.alpha_range));
    const auto& stops = coolwarm_stops();
    glUniform3fv(p.loc("u_colormap"), kColormapStops, stops[0].data());
    p.set("u_crack_tint", kCrackTint);
    p.set("u_unlit", options.is_unlit ? 1 : 0);
    p.set("u_eye", camera.position);
    p.set("u_key_dir", key);
    p.set("u_fill_dir", fill);
    p.set("u_rim_dir", rim);
    p.set("u_key_color", kKeyColor);
    p.set("u_fill_color", kFillColor);
    p.set("u_rim_color", kRimColor);
    p.set("u_sky_color", kSkyColor);
    p.set("u_bounce_color", kBounceColor);
    p.set("u_exposure", kExposure);
    p.set("u_shadow_map", 0);
    p.set("u_light_view_proj", light_view_proj);
    p.set("u_shadow_texel", 1.0f / kShadowMapSize);
    p.set("u_shadow_radius", kShadowRadiusTexels);
    const float texel_world = 2.0f * std::max(stage.radius(), 1e-6f) * 1.1f / kShadowMapSize;
    p.set("u_shadow_offset", 1.5f * texel_world);
    p.set("u_stage_y", stage.is_empty() ? 0.0f : stage.min.y(),
          stage.is_empty() ? 1.0f : stage.max.y());
}

RenderedImage Renderer::render(const Camera& camera) {
    Impl& r = *m_impl;
    r.make_current();
    const int w = r.params.width, h = r.params.height;
    const float aspect = float(w) / float(h);
    const Bounds& stage = r.stage;
    const bool has_stage = !stage.is_empty();
    const Vec3f center = has_stage ? stage.center() : camera.target;
    const float radius = has_stage ? std::max(stage.radius(), 1e-4f) : 1.0f;

    // camera-relative light rig: key from the upper left front, fill from the right, rim behind
    const Vec3f up(0, 1, 0);
    Vec3f back = camera.position - camera.target;
    back.y() = 0;
    back = back.norm() > 1e-6f ? Vec3f(back.normalized()) : Vec3f(0, 0, 1);
    const Vec3f right = up.cross(back).normalized();
    const Vec3f key = (-0.55f * right + 1.0f * up + 0.60f * back).normalized();
    const Vec3f fill = (0.85f * right + 0.35f * up + 0.50f * back).normalized();
    const Vec3f rim = (0.30f * right + 0.35f * up - 1.00f * back).normalized();

    // shadow map: orthographic view of the stage's bounding sphere from the key light
    const float shadow_r = radius * 1.1f;
    const Eigen::Matrix4f light_view = look_at(center + key * 2.0f * shadow_r, center, up);
    const Eigen::Matrix4f light_proj =
        ortho_matrix(-shadow_r, shadow_r, -shadow_r, shadow_r, 0.5f * shadow_r, 3.5f * shadow_r);
    const Eigen::Matrix4f light_view_proj = light_proj * light_view;
    r.draw_shadow_pass(light_view, light_proj);

    // camera clip range: the stage and the ground around it
    const float ground_radius = 3.0f * radius;
    const float dist = (camera.position - center).norm();
    const float far = dist + 1.5f * ground_radius + radius;
    const float near =
        std::max(far * 1e-4f, std::min(0.05f * dist, std::max(dist - radius, 1e-4f) * 0.5f));
    const Eigen::Matrix4f view = view_matrix(camera);
    const Eigen::Matrix4f proj = perspective_matrix(camera.fov_deg, aspect, near, far);
    const Eigen::Matrix4f view_proj = proj * view;

    glBindFramebuffer(GL_FRAMEBUFFER, r.msaa_fbo);
    glViewport(0, 0, w, h);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r.shadow_tex);
    glClear(GL_DEPTH_BUFFER_BIT);

    // background gradient (no depth)
    glDisable(GL_DEPTH_TEST);
    glUseProgram(r.background.id);
    r.background.set("u_top", kBackgroundTop);
    r.background.set("u_bottom", kBackgroundBottom);
    r.background.set("u_aspect", aspect);
    glBindVertexArray(r.empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);

    // meshes
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glUseProgram(r.mesh.id);
    r.set_shading_uniforms(r.mesh, camera, light_view_proj, key, fill, rim);
    r.mesh.set("u_view_proj", view_proj);
    for (const GpuMesh& g : r.meshes) {
        glBindVertexArray(g.vao);
        // absent attributes read a constant: dry, neutral hardening
        if (!g.has_saturation) glVertexAttrib1f(2, 0.0f);
        if (!g.has_alpha) glVertexAttrib1f(3, r.options.alpha0);
        r.mesh.set("u_is_crack", g.kind == SurfaceKind::Crack ? 1 : 0);
        glDrawElements(GL_TRIANGLES, g.index_count, GL_UNSIGNED_INT, nullptr);
    }

    // particles as ray-cast sphere impostors, the ground plane, then the image
    r.draw_sprites(camera, view, proj, light_view_proj, key, fill, rim);
    if (r.options.has_ground && has_stage)
        r.draw_ground(camera, view_proj, light_view_proj, key, fill, rim, center, radius,
                      ground_radius);
    return r.read_back(w, h);
}

// particles as ray-cast sphere impostors, silhouettes anti-aliased by alpha-to-coverage
void Renderer::Impl::draw_sprites(const Camera& camera, const Eigen::Matrix4f& view,
                                  const Eigen::Matrix4f& proj,
                                  const Eigen::Matrix4f& light_view_proj, const Vec3f& key,
                                  const Vec3f& fill, const Vec3f& rim) {
    if (sprite_count == 0) return;
    glUseProgram(sprite.id);
    set_shading_uniforms(sprite, camera, light_view_proj, key, fill, rim);
    sprite.set("u_view", view);
    sprite.set("u_proj", proj);
    sprite.set("u_world_from_view", Eigen::Matrix4f(view.inverse()));
    sprite.set("u_radius", sprite_radius);
    const float pixel_angle =
        2.0f * std::tan(0.5f * camera.fov_deg * float(kPi) / 180.0f) / float(params.height);
    sprite.set("u_pixel_angle", pixel_angle);
    glBindVertexArray(sprite_vao);
    if (!sprite_has_saturation) glVertexAttrib1f(1, 0.0f);
    if (!sprite_has_alpha) glVertexAttrib1f(2, options.alpha0);
    if (samples > 1) glEnable(GL_SAMPLE_ALPHA_TO_COVERAGE);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(sprite_count));
    glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
}

// ground plane at the stage's lowest point, blended into the background, no coverage
void Renderer::Impl::draw_ground(const Camera& camera, const Eigen::Matrix4f& view_proj,
                                 const Eigen::Matrix4f& light_view_proj, const Vec3f& key,
                                 const Vec3f& fill, const Vec3f& rim, const Vec3f& center,
                                 float radius, float ground_radius) {
    glUseProgram(ground.id);
    set_shading_uniforms(ground, camera, light_view_proj, key, fill, rim);
    ground.set("u_view_proj", view_proj);
    // a hair below the lowest point so a flat bottom does not z-fight with the floor
    ground.set("u_ground_center", Vec3f(center.x(), stage.min.y() - 1e-4f * radius, center.z()));
    ground.set("u_ground_radius", ground_radius);
    ground.set("u_ground_color", kGroundColor);
    ground.set("u_grid_step", std::pow(10.0f, std::round(std::log10(radius * 0.3f))));
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDisable(GL_BLEND);
}

RenderedImage Renderer::Impl::read_back(int w, int h) {
    // resolve MSAA: color, then the coverage mask
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo);
    for (int a = 0; a < 2; ++a) {
        const GLenum attachment = GLenum(GL_COLOR_ATTACHMENT0 + a);
        const GLenum draw[2] = {a == 0 ? attachment : GLenum(GL_NONE),
                                a == 1 ? attachment : GLenum(GL_NONE)};
        glReadBuffer(attachment);
        glDrawBuffers(2, draw);
        glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    }

    // read back, flipping GL's bottom-up rows to top row first
    RenderedImage img;
    img.width = w;
    img.height = h;
    std::vector<uint8_t> rgba(size_t(w) * h * 4), cov(size_t(w) * h);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w, h, GL_RED, GL_UNSIGNED_BYTE, cov.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("render");
    img.rgba.resize(rgba.size());
    img.coverage.resize(cov.size());
    for (int y = 0; y < h; ++y) {
        const size_t src = size_t(h - 1 - y) * w, dst = size_t(y) * w;
        std::copy_n(&rgba[src * 4], size_t(w) * 4, &img.rgba[dst * 4]);
        std::copy_n(&cov[src], size_t(w), &img.coverage[dst]);
        for (int x = 0; x < w; ++x) img.rgba[(dst + x) * 4 + 3] = 255;
    }
    return img;
}

}  // namespace mudcrack
