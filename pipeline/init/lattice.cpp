#include "pipeline/init/lattice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "pipeline/init/tet_mesh_ops.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

/// A uniform double in [0, 1) from mt19937's raw output (the standard fixes mt19937's sequence
/// but not uniform_real_distribution's, so this keeps jitter identical across compilers).
Real uniform01(std::mt19937& rng) { return static_cast<Real>(rng()) / 4294967296.0; }

/// A uniform point in the unit ball (rejection from the cube).
Vec3 uniform_in_ball(std::mt19937& rng) {
    for (;;) {
        const Vec3 p(2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1);
        if (p.squaredNorm() <= 1) return p;
    }
}

/// For each vertex, the tets that use it (CSR: tets of v are ids[offset[v] .. offset[v+1])).
struct VertexTets {
    std::vector<int32_t> offset, ids;
};

VertexTets vertex_tets(size_t n_vertices, const std::vector<Tet>& tets) {
    VertexTets vt;
    vt.offset.assign(n_vertices + 1, 0);
    for (const Tet& t : tets)
        for (int32_t v : t) ++vt.offset[v + 1];
    for (size_t v = 0; v < n_vertices; ++v) vt.offset[v + 1] += vt.offset[v];
    vt.ids.resize(vt.offset.back());
    std::vector<int32_t> fill(vt.offset.begin(), vt.offset.end() - 1);
    for (size_t t = 0; t < tets.size(); ++t)
        for (int32_t v : tets[t]) vt.ids[fill[v]++] = static_cast<int32_t>(t);
    return vt;
}

std::string num(Real v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

std::string vec_text(const Vec3& v) {
    std::ostringstream s;
    s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
    return s.str();
}

/// No move of a lattice point (the rim's snap, the jitter) may leave a tet with less than this
/// share of its rest volume.
constexpr Real kMinVolumeFraction = 0.2;

/// The ellipse inscribed in a box's x-z rectangle.
struct InscribedEllipse {
    explicit InscribedEllipse(const BoxSource& box)
        : centre((box.min + box.max) / 2),
          semi((box.max - box.min) / 2) {}
    /// The square of (x, z)'s radius in the ellipse's own units: 1 on it, below 1 inside.
    Real radius2(Real x, Real z) const {
        const Real u = (x - centre.x()) / semi.x(), w = (z - centre.z()) / semi.z();
        return u * u + w * w;
    }
    Vec3 centre, semi;
};

/// The lattice's columns of cells (i, k), nx x nz, that a box's footprint keeps: all of them for
/// the rectangle, those whose centre lies in the inscribed ellipse for the ellipse.
class FootprintColumns {
public:
    FootprintColumns(const BoxSource& box, int nx, int nz, const Vec3& step)
        : m_nx(nx),
          m_nz(nz),
          m_is_kept(static_cast<size_t>(nx) * nz, 1) {
        if (box.footprint != Footprint::Ellipse) return;
        const InscribedEllipse ellipse(box);
        for (int k = 0; k < nz; ++k)
            for (int i = 0; i < nx; ++i)
                m_is_kept[i + nx * k] =
                    ellipse.radius2(box.min.x() + (i + Real(0.5)) * step.x(),
                                    box.min.z() + (k + Real(0.5)) * step.z()) <= 1;
    }
    bool is_kept(int i, int k) const {
        return i >= 0 && i < m_nx && k >= 0 && k < m_nz && m_is_kept[i + m_nx * k];
    }
    /// How many of the 4 columns of cells around the lattice column of points (i, k) are kept:
    /// 0, it is unused; 4, it is inside; between, it is on the rim (the box's sides, for the
    /// rectangle).
    int kept_around(int i, int k) const {
        return is_kept(i - 1, k - 1) + is_kept(i, k - 1) + is_kept(i - 1, k) + is_kept(i, k);
    }
    /// The Kuhn tets of the kept cells (kuhn_tets writes 6 per cell, x fastest, then y, then z).
    std::vector<Tet> kept_tets(const std::vector<Tet>& tets, int ny) const {
        std::vector<Tet> kept;
        kept.reserve(tets.size());
        for (size_t t = 0; t < tets.size(); ++t) {
            const size_t cell = t / 6;
            if (is_kept(static_cast<int>(cell % m_nx),
                        static_cast<int>(cell / (static_cast<size_t>(m_nx) * ny))))
                kept.push_back(tets[t]);
        }
        return kept;
    }

private:
    int m_nx, m_nz;
    std::vector<char> m_is_kept;
};

/// True if every tet of vertex v keeps more than min_volume [m^3].
bool incident_tets_keep(const TetMesh& mesh, const VertexTets& vt, int32_t v, Real min_volume) {
    for (int32_t e = vt.offset[v]; e < vt.offset[v + 1]; ++e) {
        const Tet& t = mesh.tets[vt.ids[e]];
        if (!(signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]) >
              min_volume))
            return false;
    }
    return true;
}

/// The rim's staircase of cells onto the ellipse inscribed in the box: each rim column of points
/// moves as one (the side stays vertical) along the ray from the centre; where two rim points
/// would meet (the staircase runs radially near the axes), or a corner cell's tets would be
/// squashed, the move is cut short, by eighths, until its tets keep min_volume.
void snap_rim_to_ellipse(const BoxSource& box, const int n[3], const FootprintColumns& columns,
                         const VertexTets& vt, Real min_volume, TetMesh& mesh) {
    const InscribedEllipse ellipse(box);
    const Vec3& centre = ellipse.centre;
    for (int k = 0; k <= n[2]; ++k)
        for (int i = 0; i <= n[0]; ++i) {
            const int kept = columns.kept_around(i, k);
            if (kept == 0 || kept == 4) continue;
            const Vec3 rest = mesh.X[lattice_index(i, 0, k, n[0], n[1])];
            const Real radius = std::sqrt(ellipse.radius2(rest.x(), rest.z()));
            if (!(radius > 0)) continue;
            const Real to_x = centre.x() + (rest.x() - centre.x()) / radius;
            const Real to_z = centre.z() + (rest.z() - centre.z()) / radius;
            for (int eighths = 8; eighths >= 0; --eighths) {
                const Real fraction = eighths / Real(8);
                for (int j = 0; j <= n[1]; ++j) {
                    Vec3& x = mesh.X[lattice_index(i, j, k, n[0], n[1])];
                    x.x() = rest.x() + fraction * (to_x - rest.x());
                    x.z() = rest.z() + fraction * (to_z - rest.z());
                }
                bool is_ok = true;
                for (int j = 0; j <= n[1] && is_ok; ++j)
                    is_ok = incident_tets_keep(mesh, vt, lattice_index(i, j, k, n[0], n[1]),
                                               min_volume);
                if (is_ok) break;
            }
        }
}

/// Moves the interior points (inside the footprint, off its rim, off the top and bottom) by up
/// to radius, seeded; a move that would leave a tet below min_volume is re-drawn, and after a
/// few tries the point stays put. The body's faces stay flat and its volume that of its tets.
void jitter_interior(const int n[3], const FootprintColumns& columns, const VertexTets& vt,
                     Real radius, Real min_volume, unsigned seed, TetMesh& mesh) {
    constexpr int kTries = 8;
    std::mt19937 rng(seed);
    for (int k = 1; k < n[2]; ++k)
        for (int j = 1; j < n[1]; ++j)
            for (int i = 1; i < n[0]; ++i) {
                if (columns.kept_around(i, k) != 4) continue;
                const int32_t v = lattice_index(i, j, k, n[0], n[1]);
                const Vec3 rest = mesh.X[v];
                for (int attempt = 0; attempt < kTries; ++attempt) {
                    mesh.X[v] = rest + radius * uniform_in_ball(rng);
                    if (incident_tets_keep(mesh, vt, v, min_volume)) break;
                    mesh.X[v] = rest;
                }
            }
}

}  // namespace

std::string count_text(double count) {
    char text[64];
    std::snprintf(text, sizeof text, "%.0f", count);
    return text;
}

double lattice_cells(Real extent, Real spacing) {
    return std::max(1.0, std::round(extent / spacing));
}

std::vector<Tet> kuhn_tets(int nx, int ny, int nz) {
    // the 6 monotone paths from corner (0,0,0) to (1,1,1), one per axis permutation; a tet's
    // orientation is the permutation's sign, so odd ones swap their last two corners
    static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},   // even
                                        {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};  // odd
    std::vector<Tet> tets;
    tets.reserve(static_cast<size_t>(6) * nx * ny * nz);
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                for (int p = 0; p < 6; ++p) {
                    int c[3] = {i, j, k};
                    Tet t;
                    t[0] = lattice_index(c[0], c[1], c[2], nx, ny);
                    for (int s = 0; s < 3; ++s) {
                        ++c[kPerm[p][s]];
                        t[s + 1] = lattice_index(c[0], c[1], c[2], nx, ny);
                    }
                    if (p >= 3) std::swap(t[2], t[3]);
                    tets.push_back(t);
                }
    return tets;
}

TetMesh make_box_tets(const BoxSource& box, unsigned seed) {
    const Vec3 extent = box.max - box.min;
    if (!(extent.minCoeff() > 0))
        throw ShotValueError("/source/box: min = " + vec_text(box.min) + ", max = " +
                             vec_text(box.max) + ": max must exceed min on every axis");
    if (!(box.spacing > 0))
        throw ShotValueError("/source/box/spacing = " + num(box.spacing) + ": must be > 0 [m]");
    const double cells[3] = {lattice_cells(extent.x(), box.spacing),
                             lattice_cells(extent.y(), box.spacing),
                             lattice_cells(extent.z(), box.spacing)};
    const double points = (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
    if (points > kMaxInitParticles)
        throw ShotValueError("/source/box/spacing = " + num(box.spacing) + ": gives " +
                             count_text(points) + " particles; expected at most " +
                             count_text(kMaxInitParticles) +
                             ": raise the spacing or shrink the box");
    const int n[3] = {int(cells[0]), int(cells[1]), int(cells[2])};
    const Vec3 step(extent.x() / n[0], extent.y() / n[1], extent.z() / n[2]);

    TetMesh mesh;
    mesh.X.resize(static_cast<size_t>(points));
    for (int k = 0; k <= n[2]; ++k)
        for (int j = 0; j <= n[1]; ++j)
            for (int i = 0; i <= n[0]; ++i)
                mesh.X[lattice_index(i, j, k, n[0], n[1])] =
                    box.min + Vec3(i * step.x(), j * step.y(), k * step.z());
    // the far faces sit exactly on max, not on min + n * step (which may round differently)
    for (int k = 0; k <= n[2]; ++k)
        for (int j = 0; j <= n[1]; ++j)
            for (int i = 0; i <= n[0]; ++i) {
                Vec3& x = mesh.X[lattice_index(i, j, k, n[0], n[1])];
                if (i == n[0]) x.x() = box.max.x();
                if (j == n[1]) x.y() = box.max.y();
                if (k == n[2]) x.z() = box.max.z();
            }
    mesh.tets = kuhn_tets(n[0], n[1], n[2]);

    const FootprintColumns columns(box, n[0], n[2], step);
    const bool is_ellipse = box.footprint == Footprint::Ellipse;
    const bool is_jittered = box.lattice == Lattice::Jittered && box.jitter > 0;
    if (is_ellipse) mesh.tets = columns.kept_tets(mesh.tets, n[1]);
    if (is_ellipse || is_jittered) {
        const Real min_volume = kMinVolumeFraction * step.prod() / 6;  // every Kuhn tet is a sixth
        const VertexTets vt = vertex_tets(mesh.X.size(), mesh.tets);
        if (is_ellipse) snap_rim_to_ellipse(box, n, columns, vt, min_volume, mesh);
        if (is_jittered)
            jitter_interior(n, columns, vt, box.jitter * step.minCoeff(), min_volume, seed, mesh);
    }
    if (is_ellipse) drop_unused_vertices(mesh);
    return mesh;
}

TetMesh make_column_lattice_tets(Real x0, Real z0, Real sx, Real sz, int nx, int ny, int nz,
                                 const std::vector<Real>& top) {
    TetMesh mesh;
    mesh.X.resize(static_cast<size_t>(nx + 1) * (ny + 1) * (nz + 1));
    for (int k = 0; k <= nz; ++k)
        for (int i = 0; i <= nx; ++i) {
            const Real x = x0 + sx * i / nx, z = z0 + sz * k / nz;
            const Real h = top[i + (nx + 1) * k];
            if (!(h > 0)) {
                std::ostringstream msg;
                msg << "heightfield column at (x, z) = (" << x << ", " << z << ") has top y = " << h
                    << ": expected > 0";
                throw RuntimeError(msg.str());
            }
            for (int j = 0; j <= ny; ++j)
                mesh.X[lattice_index(i, j, k, nx, ny)] = Vec3(x, h * j / ny, z);
        }
    mesh.tets = kuhn_tets(nx, ny, nz);
    // stretching columns vertically keeps Kuhn tets positive for any positive heights; check
    // anyway, since a wrong sign here would silently produce negative particle volumes
    const int64_t bad = count_non_positive_tets(mesh);
    if (bad > 0)
        throw RuntimeError("heightfield lattice: " + std::to_string(bad) +
                           " tets are not positively oriented");
    return mesh;
}

}  // namespace mudcrack
