#include "render/shaders.h"

namespace mudcrack::shaders {

// Every program that shades a surface is "#version 330 core" + kShadingChunk + its own main().
const char* const kShadingChunk = R"GLSL(
// color modes (render/colormap.h holds the same conventions for the CPU side)
uniform int u_mode;                 // a MC_COLOR_MODE_* (render_params.h: color_mode_glsl_defines)
uniform vec3 u_albedo;              // dry soil, linear RGB
uniform float u_moisture_darkening; // color = albedo (1 - k s)
uniform float u_alpha0;             // hardening colormap center
uniform float u_alpha_range;        // colormap saturates at alpha0 -/+ range
uniform vec3 u_colormap[9];         // diverging colormap stops, sRGB
uniform vec3 u_crack_tint;          // crack interior = base * tint (moisture, plain modes)
uniform int u_unlit;                // 1: base color only

// light rig, directions towards the lights (camera-relative, set per view)
uniform vec3 u_eye;
uniform vec3 u_key_dir, u_fill_dir, u_rim_dir;
uniform vec3 u_key_color, u_fill_color, u_rim_color, u_sky_color, u_bounce_color;
uniform float u_exposure;

// key light shadow map
uniform sampler2DShadow u_shadow_map;
uniform mat4 u_light_view_proj;
uniform float u_shadow_texel;       // 1 / shadow map size
uniform float u_shadow_radius;      // PCF disk radius [texels]
uniform float u_shadow_offset;      // normal offset of the lookup [m]
uniform vec2 u_stage_y;             // stage min and max y [m]

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}
vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec3 colormap(float t) {
    float x = clamp(t, 0.0, 1.0) * 8.0;
    int i = min(int(floor(x)), 7);
    return mix(u_colormap[i], u_colormap[i + 1], x - float(i));
}

// linear base color of a surface point in the current color mode
vec3 base_color(float s, float a, bool is_crack) {
    vec3 c;
    if (u_mode == MC_COLOR_MODE_HARDENING) {
        c = srgb_to_linear(colormap(0.5 + 0.5 * (a - u_alpha0) / u_alpha_range));
    } else if (u_mode == MC_COLOR_MODE_MOISTURE) {
        c = u_albedo * (1.0 - u_moisture_darkening * clamp(s, 0.0, 1.0));
    } else {
        c = u_albedo;
    }
    // hardening keeps its colormap readable inside cracks; the others show darker, warmer soil
    if (is_crack && u_mode != MC_COLOR_MODE_HARDENING) c *= u_crack_tint;
    return c;
}

// crack interiors darken with depth below the top of the stage: a cheap occlusion look
float crack_occlusion(vec3 P) {
    return mix(0.45, 1.0, smoothstep(u_stage_y.x, u_stage_y.y, P.y));
}

const vec2 kPoisson[12] = vec2[](
    vec2(-0.326, -0.406), vec2(-0.840, -0.074), vec2(-0.696, 0.457), vec2(-0.203, 0.621),
    vec2(0.962, -0.195), vec2(0.473, -0.480), vec2(0.519, 0.767), vec2(0.185, -0.893),
    vec2(0.507, 0.064), vec2(0.896, 0.412), vec2(-0.322, -0.933), vec2(-0.792, -0.598));

// fraction of the key light reaching P: 12 Poisson taps, each a hardware 2x2 PCF lookup
float key_visibility(vec3 P, vec3 N) {
    vec4 q = u_light_view_proj * vec4(P + N * u_shadow_offset, 1.0);
    vec3 p = q.xyz / q.w * 0.5 + 0.5;
    if (p.z >= 1.0) return 1.0;
    float sum = 0.0;
    for (int i = 0; i < 12; ++i)
        sum += texture(u_shadow_map, vec3(p.xy + kPoisson[i] * u_shadow_radius * u_shadow_texel, p.z));
    return sum / 12.0;
}

// filmic tone curve (Narkowicz's ACES fit), then sRGB encoding
vec3 display(vec3 x) {
    x *= u_exposure;
    x = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return linear_to_srgb(x);
}

// key (shadowed) + fill + rim + sky/bounce ambient, soil-like low specular that rises when wet
vec3 shade(vec3 P, vec3 N, vec3 base, float ao, float wetness) {
    if (u_unlit == 1) return linear_to_srgb(base);
    vec3 V = normalize(u_eye - P);
    float vis = key_visibility(P, N);
    float n_key = max(dot(N, u_key_dir), 0.0);
    vec3 ambient = mix(u_bounce_color, u_sky_color, 0.5 + 0.5 * N.y) * ao;
    vec3 c = base * (ambient + u_key_color * n_key * vis + u_fill_color * max(dot(N, u_fill_dir), 0.0) * ao);
    vec3 H = normalize(u_key_dir + V);
    float gloss = mix(10.0, 60.0, wetness);
    c += u_key_color * (0.025 + 0.2 * wetness) * pow(max(dot(N, H), 0.0), gloss) * n_key * vis;
    float fresnel = pow(1.0 - max(dot(N, V), 0.0), 3.0);
    c += (0.6 * base + 0.08) * u_rim_color * max(dot(N, u_rim_dir), 0.0) * (0.2 + 0.8 * fresnel) * ao;
    return display(c);
}
)GLSL";

const char* const kBackgroundVertex = R"GLSL(
out vec2 v_uv;
void main() {
    // one triangle covering the screen
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    v_uv = p * 0.5 + 0.5;
    gl_Position = vec4(p, 0.0, 1.0);
}
)GLSL";

const char* const kBackgroundFragment = R"GLSL(
in vec2 v_uv;
uniform vec3 u_top, u_bottom;   // display-space colors
uniform float u_aspect;
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_coverage;
void main() {
    vec3 c = mix(u_bottom, u_top, smoothstep(0.0, 1.0, v_uv.y));
    vec2 d = (v_uv - 0.5) * vec2(u_aspect, 1.0);
    c *= 1.0 - 0.22 * smoothstep(0.35, 1.1, length(d));          // soft vignette
    // ordered dither against banding (deterministic: goldens stay stable)
    float n = fract(52.9829189 * fract(dot(gl_FragCoord.xy, vec2(0.06711056, 0.00583715))));
    o_color = vec4(c + (n - 0.5) / 255.0, 1.0);
    o_coverage = vec4(0.0);
}
)GLSL";

const char* const kMeshVertex = R"GLSL(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_saturation;
layout(location = 3) in float a_alpha;
uniform mat4 u_view_proj;
out vec3 v_position;
out vec3 v_normal;
out float v_saturation;
out float v_alpha;
void main() {
    v_position = a_position;
    v_normal = a_normal;
    v_saturation = a_saturation;
    v_alpha = a_alpha;
    gl_Position = u_view_proj * vec4(a_position, 1.0);
}
)GLSL";

const char* const kMeshFragment = R"GLSL(
in vec3 v_position;
in vec3 v_normal;
in float v_saturation;
in float v_alpha;
uniform int u_is_crack;
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_coverage;
void main() {
    // orient the shading normal to the visible side of the triangle: robust to any winding
    vec3 face = cross(dFdx(v_position), dFdy(v_position));
    vec3 N = normalize(v_normal);
    if (dot(face, u_eye - v_position) < 0.0) face = -face;
    if (dot(N, face) < 0.0) N = -N;
    bool is_crack = u_is_crack == 1;
    vec3 base = base_color(v_saturation, v_alpha, is_crack);
    float ao = is_crack ? crack_occlusion(v_position) : 1.0;
    float wetness = u_mode == MC_COLOR_MODE_MOISTURE ? clamp(v_saturation, 0.0, 1.0) : 0.0;
    o_color = vec4(shade(v_position, N, base, ao, wetness), 1.0);
    o_coverage = vec4(1.0);
}
)GLSL";

const char* const kMeshShadowVertex = R"GLSL(
layout(location = 0) in vec3 a_position;
uniform mat4 u_light_view_proj;
void main() { gl_Position = u_light_view_proj * vec4(a_position, 1.0); }
)GLSL";

const char* const kDepthOnlyFragment = R"GLSL(
void main() {}
)GLSL";

const char* const kSpriteVertex = R"GLSL(
layout(location = 0) in vec3 a_center;
layout(location = 1) in float a_saturation;
layout(location = 2) in float a_alpha;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_radius;
out vec3 v_ray;              // view-space point on the impostor quad
flat out vec3 v_center;      // view-space sphere center
flat out float v_saturation;
flat out float v_alpha;
const vec2 kCorners[4] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(1, 1));
void main() {
    vec3 c = (u_view * vec4(a_center, 1.0)).xyz;
    // a quad in front of the sphere, wide enough for its perspective silhouette
    vec3 p = c + vec3(kCorners[gl_VertexID] * u_radius * 1.5, u_radius);
    v_ray = p;
    v_center = c;
    v_saturation = a_saturation;
    v_alpha = a_alpha;
    gl_Position = u_proj * vec4(p, 1.0);
}
)GLSL";

const char* const kSpriteFragment = R"GLSL(
in vec3 v_ray;
flat in vec3 v_center;
flat in float v_saturation;
flat in float v_alpha;
uniform mat4 u_proj;
uniform mat4 u_world_from_view;
uniform float u_radius;
uniform float u_pixel_angle;    // view-space size of a pixel at unit depth
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_coverage;
void main() {
    // ray from the eye (origin of view space) against the sphere
    vec3 d = normalize(v_ray);
    float b = dot(d, v_center);
    float miss2 = dot(v_center, v_center) - b * b;   // squared distance of the ray from the center
    float miss = sqrt(max(miss2, 0.0));
    float pixel = u_pixel_angle * b;
    // anti-aliased silhouette through alpha-to-coverage
    float edge = clamp((u_radius - miss) / pixel + 0.5, 0.0, 1.0);
    if (edge <= 0.0) discard;
    float t = b - sqrt(max(u_radius * u_radius - miss2, 0.0));
    vec3 hit = d * t;
    vec3 n_view = normalize(hit - v_center);
    vec4 clip = u_proj * vec4(hit, 1.0);
    gl_FragDepth = clip.z / clip.w * 0.5 + 0.5;
    vec3 P = (u_world_from_view * vec4(hit, 1.0)).xyz;
    vec3 N = normalize(mat3(u_world_from_view) * n_view);
    vec3 base = base_color(v_saturation, v_alpha, false);
    float wetness = u_mode == MC_COLOR_MODE_MOISTURE ? clamp(v_saturation, 0.0, 1.0) : 0.0;
    o_color = vec4(shade(P, N, base, 1.0, wetness), edge);
    o_coverage = vec4(1.0, 0.0, 0.0, edge);
}
)GLSL";

const char* const kSpriteShadowVertex = R"GLSL(
layout(location = 0) in vec3 a_center;
uniform mat4 u_light_view;
uniform mat4 u_light_proj;
uniform float u_radius;
out vec2 v_corner;
const vec2 kCorners[4] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(1, 1));
void main() {
    // a disk facing the (orthographic) key light
    vec3 c = (u_light_view * vec4(a_center, 1.0)).xyz;
    v_corner = kCorners[gl_VertexID];
    gl_Position = u_light_proj * vec4(c + vec3(v_corner * u_radius, 0.0), 1.0);
}
)GLSL";

const char* const kSpriteShadowFragment = R"GLSL(
in vec2 v_corner;
void main() {
    if (dot(v_corner, v_corner) > 1.0) discard;
}
)GLSL";

const char* const kGroundVertex = R"GLSL(
uniform vec3 u_ground_center;   // [m]
uniform float u_ground_radius;  // half size of the square [m]
uniform mat4 u_view_proj;
out vec3 v_position;
void main() {
    vec2 k = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1)) * 2.0 - 1.0;
    v_position = u_ground_center + vec3(k.x, 0.0, k.y) * u_ground_radius;
    gl_Position = u_view_proj * vec4(v_position, 1.0);
}
)GLSL";

const char* const kGroundFragment = R"GLSL(
in vec3 v_position;
uniform vec3 u_ground_center;
uniform float u_ground_radius;
uniform vec3 u_ground_color;    // linear
uniform float u_grid_step;      // [m]; 0: no grid
layout(location = 0) out vec4 o_color;
void main() {
    vec3 N = vec3(0.0, 1.0, 0.0);
    vec3 c = u_ground_color;
    if (u_grid_step > 0.0) {
        // anti-aliased grid lines, one pixel wide
        vec2 g = v_position.xz / u_grid_step;
        vec2 w = max(fwidth(g), vec2(1e-6));
        vec2 d = abs(fract(g - 0.5) - 0.5) / w;
        float line = 1.0 - min(min(d.x, d.y), 1.0);
        c *= 1.0 - 0.12 * line;
    }
    vec3 rgb = shade(v_position, N, c, 1.0, 0.0);
    // fade the floor into the background so it has no visible edge
    float r = length(v_position.xz - u_ground_center.xz) / u_ground_radius;
    o_color = vec4(rgb, 1.0 - smoothstep(0.35, 0.95, r));
}
)GLSL";

}  // namespace mudcrack::shaders
