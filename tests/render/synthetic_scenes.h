#pragma once
/// Small synthetic scenes for the render tests and benchmark: a UV sphere, a subdivided slab,
/// a cracked slab, a particle ball. Deterministic, no files.
#include <cmath>
#include <vector>

#include "render/scene.h"

namespace mudcrack::test {

/// A UV sphere of `radius` at `center` with outward normals; saturation = (1 - y_unit)/2 (wet at
/// the bottom), alpha = alpha_scale * x_unit (compressed at -x, stretched at +x).
inline TriMesh uv_sphere(const Vec3f& center, float radius, int rings, int segments,
                         float alpha_scale = 0.5f) {
    TriMesh m;
    m.name = "boundary";
    const float pi = 3.14159265358979f;
    for (int i = 0; i <= rings; ++i) {
        const float th = pi * float(i) / float(rings);
        for (int j = 0; j <= segments; ++j) {
            const float ph = 2 * pi * float(j) / float(segments);
            const Vec3f n(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
            m.positions.push_back(center + radius * n);
            m.normals.push_back(n);
            m.uvs.push_back(Vec2f(float(j) / float(segments), float(i) / float(rings)));
            m.saturation.push_back(0.5f * (1.0f - n.y()));
            m.alpha.push_back(alpha_scale * n.x());
        }
    }
    const int row = segments + 1;
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const int a = i * row + j, b = a + row;
            // CCW seen from outside
            if (i != 0) m.faces.push_back({a, a + 1, b});
            if (i != rings - 1) m.faces.push_back({a + 1, b + 1, b});
        }
    return m;
}

/// A flat, upward-facing square patch [x0,x1]x[z0,z1] at height y with n x n cells, every vertex
/// carrying saturation `s` and alpha `a`.
inline TriMesh flat_patch(float x0, float x1, float z0, float z1, float y, int n, float s,
                          float a) {
    TriMesh m;
    m.name = "boundary";
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            m.positions.push_back(Vec3f(x0 + (x1 - x0) * float(j) / float(n), y,
                                        z0 + (z1 - z0) * float(i) / float(n)));
            m.normals.push_back(Vec3f(0, 1, 0));
            m.saturation.push_back(s);
            m.alpha.push_back(a);
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const int a0 = i * (n + 1) + j, b0 = a0 + n + 1;
            m.faces.push_back({a0, b0, a0 + 1});  // CCW seen from +y
            m.faces.push_back({a0 + 1, b0, b0 + 1});
        }
    return m;
}

/// A closed box [min, max] with per-face normals, saturation and alpha given per vertex by fn.
template <class Fn>
TriMesh box_mesh(const Vec3f& lo, const Vec3f& hi, const char* name, Fn&& attributes) {
    TriMesh m;
    m.name = name;
    const Vec3f n[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const Vec3f& nn : n) {
        // two in-plane axes u x v = n so the quad is CCW seen from outside
        const int k = nn.x() != 0 ? 0 : nn.y() != 0 ? 1 : 2;
        Vec3f u = Vec3f::Zero(), v = Vec3f::Zero();
        u[(k + 1) % 3] = 1;
        v[(k + 2) % 3] = 1;
        if (nn[k] < 0) std::swap(u, v);
        const Vec3f c = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
        const Vec3f fc = c + nn.cwiseProduct(half);
        const int base = int(m.positions.size());
        for (int q = 0; q < 4; ++q) {
            const float su = (q == 1 || q == 2) ? 1.f : -1.f, sv = (q >= 2) ? 1.f : -1.f;
            const Vec3f p = fc + su * u.cwiseProduct(half) + sv * v.cwiseProduct(half);
            float s = 0, a = 0;
            attributes(p, s, a);
            m.positions.push_back(p);
            m.normals.push_back(nn);
            m.saturation.push_back(s);
            m.alpha.push_back(a);
        }
        m.faces.push_back({base, base + 1, base + 2});
        m.faces.push_back({base, base + 2, base + 3});
    }
    return m;
}

/// A ball of particles on a jittered-free lattice with spacing `h`; saturation grows with
/// height, alpha with x.
inline ParticleSprites particle_ball(const Vec3f& center, float radius, float h) {
    ParticleSprites ps;
    ps.radius = 0.5f * h;
    const int n = int(std::ceil(radius / h));
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                const Vec3f q(float(i) * h, float(j) * h, float(k) * h);
                if (q.norm() > radius) continue;
                ps.positions.push_back(center + q);
                ps.saturation.push_back(0.5f + 0.5f * q.y() / radius);
                ps.alpha.push_back(0.5f * q.x() / radius);
            }
    return ps;
}

}  // namespace mudcrack::test
