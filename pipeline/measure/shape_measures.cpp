#include "pipeline/measure/shape_measures.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "sim/core/error.h"

namespace mudcrack {

RestColumns build_rest_columns(const std::vector<Vec3>& rest, Real width) {
    if (!(width > 0)) throw InputError("rest columns: width = " + std::to_string(width) + ": expected > 0");
    RestColumns columns;
    columns.width = width;
    const int32_t n = static_cast<int32_t>(rest.size());
    std::vector<std::pair<int64_t, int64_t>> cell(n);
    for (int32_t p = 0; p < n; ++p)
        cell[p] = {static_cast<int64_t>(std::floor(rest[p].x() / width)),
                   static_cast<int64_t>(std::floor(rest[p].z() / width))};
    columns.particle.resize(n);
    std::iota(columns.particle.begin(), columns.particle.end(), 0);
    std::sort(columns.particle.begin(), columns.particle.end(), [&](int32_t a, int32_t b) {
        if (cell[a] != cell[b]) return cell[a] < cell[b];
        if (rest[a].y() != rest[b].y()) return rest[a].y() < rest[b].y();
        return a < b;
    });
    columns.begin.push_back(0);
    for (int32_t k = 1; k < n; ++k)
        if (cell[columns.particle[k]] != cell[columns.particle[k - 1]]) columns.begin.push_back(k);
    if (n > 0) columns.begin.push_back(n);
    return columns;
}

Real particle_spacing(const std::vector<Real>& rest_volume) {
    if (rest_volume.empty()) return 0;
    const Real mean = std::accumulate(rest_volume.begin(), rest_volume.end(), Real(0)) / rest_volume.size();
    return std::cbrt(mean);
}

namespace {

/// The q-quantile (0..1) of v by the nearest-rank rule; v is reordered.
Real quantile(std::vector<Real>& v, Real q) {
    if (v.empty()) return 0;
    const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<Real>(v.size())));
    const size_t k = std::min(v.size(), std::max<size_t>(rank, 1)) - 1;
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
}

}  // namespace

LayerShape measure_layer_shape(const RestColumns& columns, const std::vector<Vec3>& rest,
                               const std::vector<Vec3>& x, Real gap) {
    if (rest.size() != x.size())
        throw InputError("layer shape: " + std::to_string(x.size()) + " current positions for " +
                         std::to_string(rest.size()) + " rest positions");
    LayerShape shape;
    shape.columns = columns.n_columns();
    if (shape.columns == 0) return shape;
    std::vector<Real> top_rise;
    top_rise.reserve(shape.columns);
    int32_t split = 0, lifted = 0;
    for (int32_t c = 0; c < shape.columns; ++c) {
        const int32_t b = columns.begin[c], e = columns.begin[c + 1];
        const int32_t bottom = columns.particle[b], top = columns.particle[e - 1];
        top_rise.push_back(x[top].y() - rest[top].y());
        if (x[bottom].y() - rest[bottom].y() > gap) ++lifted;
        for (int32_t k = b + 1; k < e; ++k) {
            const int32_t lo = columns.particle[k - 1], hi = columns.particle[k];
            const Real opening = (x[hi].y() - x[lo].y()) - (rest[hi].y() - rest[lo].y());
            if (opening > gap) {
                ++split;
                break;
            }
        }
    }
    shape.split_fraction = Real(split) / shape.columns;
    shape.lifted_fraction = Real(lifted) / shape.columns;
    shape.top_rise_median = quantile(top_rise, 0.5);
    shape.top_rise_p95 = quantile(top_rise, 0.95);
    shape.curl = shape.top_rise_p95 - shape.top_rise_median;
    return shape;
}

FragmentSizes measure_fragment_sizes(const Fragments& fragments, const std::vector<Real>& rest_volume) {
    if (fragments.id.size() != rest_volume.size())
        throw InputError("fragment sizes: " + std::to_string(fragments.id.size()) + " labels for " +
                         std::to_string(rest_volume.size()) + " particle volumes");
    FragmentSizes sizes;
    sizes.count = fragments.count;
    std::vector<Real> volume(fragments.count, 0);
    for (size_t p = 0; p < rest_volume.size(); ++p)
        if (fragments.id[p] >= 0) volume[fragments.id[p]] += rest_volume[p];
    Real sum = 0, sum_sq = 0, largest = 0;
    for (Real v : volume) {
        sum += v;
        sum_sq += v * v;
        largest = std::max(largest, v);
    }
    sizes.total_volume = sum;
    if (sum > 0) {
        sizes.largest_fraction = largest / sum;
        sizes.weighted_mean_volume = sum_sq / sum;
    }
    return sizes;
}

namespace {

/// Fewer top particles than this are crumbs, not polygons: a lone top particle is usually a
/// column edge artefact of the jittered lattice (a column whose top particle sits low).
constexpr int kMinPolygonParticles = 4;

/// Union-find with path halving; the root of a set is its smallest element (deterministic ids).
int32_t find_root(std::vector<int32_t>& parent, int32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
}

}  // namespace

SurfacePolygons measure_surface_polygons(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                         const RestColumns& columns, int min_particles) {
    if (static_cast<int32_t>(is_broken.size()) != topo.n_edges())
        throw InputError("surface polygons: " + std::to_string(is_broken.size()) + " edge flags for " +
                         std::to_string(topo.n_edges()) + " edges");
    if (static_cast<int32_t>(columns.particle.size()) != topo.n_particles)
        throw InputError("surface polygons: columns hold " + std::to_string(columns.particle.size()) +
                         " particles, the mesh " + std::to_string(topo.n_particles));
    std::vector<uint8_t> on_top(topo.n_particles, 0);
    SurfacePolygons polygons;
    for (int32_t c = 0; c < columns.n_columns(); ++c) {
        const Real top_y = topo.X[columns.particle[columns.begin[c + 1] - 1]].y();
        for (int32_t k = columns.begin[c]; k < columns.begin[c + 1]; ++k) {
            const int32_t p = columns.particle[k];
            if (topo.X[p].y() > top_y - 2 * columns.width) {
                on_top[p] = 1;
                ++polygons.top_particles;
            }
        }
    }
    std::vector<int32_t> parent(topo.n_particles);
    std::iota(parent.begin(), parent.end(), 0);
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        if (is_broken[e] || !on_top[p] || !on_top[q]) continue;
        const int32_t a = find_root(parent, p), b = find_root(parent, q);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
    std::vector<int32_t> size(topo.n_particles, 0);
    for (int32_t p = 0; p < topo.n_particles; ++p)
        if (on_top[p]) ++size[find_root(parent, p)];
    // each top particle stands for an equal share of the footprint (columns x width^2)
    const Real particle_area = polygons.top_particles > 0 ? columns.n_columns() * columns.width * columns.width /
                                                                polygons.top_particles
                                                          : 0;
    Real sum = 0, sum_sq = 0, largest = 0;
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        if (size[p] < std::max(min_particles, kMinPolygonParticles)) continue;
        const Real area = size[p] * particle_area;
        ++polygons.count;
        sum += area;
        sum_sq += area * area;
        largest = std::max(largest, area);
    }
    if (sum > 0) {
        polygons.weighted_mean_area = sum_sq / sum;
        polygons.largest_fraction = largest / sum;
    }
    return polygons;
}

}  // namespace mudcrack
