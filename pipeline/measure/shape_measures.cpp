#include "pipeline/measure/shape_measures.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>

#include <Eigen/Eigenvalues>

#include "sim/core/error.h"

namespace mudcrack {
namespace {

// a set of pieces by size (volume or area): what a fragmentation or a crack pattern is measured by
struct SizeSummary {
    Real total = 0;
    Real weighted_mean = 0;     // sum s^2 / sum s: the size of the piece a random point lies in
    Real largest_fraction = 0;  // the largest piece's share of the total
};

SizeSummary summarize_sizes(const std::vector<Real>& sizes) {
    Real sum = 0, sum_sq = 0, largest = 0;
    for (Real s : sizes) {
        sum += s;
        sum_sq += s * s;
        largest = std::max(largest, s);
    }
    SizeSummary summary;
    summary.total = sum;
    if (sum > 0) {
        summary.weighted_mean = sum_sq / sum;
        summary.largest_fraction = largest / sum;
    }
    return summary;
}

// A lattice's columns along one axis: the lowest coordinate and the pitch (0: not a lattice).
struct LatticeAxis {
    Real first = 0;
    Real pitch = 0;
};

// Rest coordinate `axis` of the particles as a lattice: when they take at most half as many
// distinct values as there are particles (on a lattice, a plane of particles shares each one; a
// jittered lattice or a mesh gives nearly every particle its own) and those values lie within a
// hundredth of a pitch of first + k pitch.
LatticeAxis lattice_axis(const std::vector<Vec3>& rest, int axis) {
    std::vector<Real> v(rest.size());
    for (size_t p = 0; p < rest.size(); ++p) v[p] = rest[p][axis];
    std::sort(v.begin(), v.end());
    if (v.size() < 4 || !(v.back() > v.front())) return {};
    const Real same = 1e-9 * (v.back() - v.front());
    std::vector<Real> distinct{v.front()};
    for (Real x : v)
        if (x - distinct.back() > same) distinct.push_back(x);
    if (distinct.size() < 2 || 2 * distinct.size() > v.size()) return {};
    const Real pitch = (distinct.back() - distinct.front()) / Real(distinct.size() - 1);
    for (size_t k = 0; k < distinct.size(); ++k)
        if (std::abs(distinct[k] - (distinct.front() + Real(k) * pitch)) > Real(0.01) * pitch)
            return {};
    return {distinct.front(), pitch};
}

}  // namespace

RestColumns build_rest_columns(const std::vector<Vec3>& rest, Real spacing) {
    if (!(spacing > 0))
        throw InputError("rest columns: width = " + std::to_string(spacing) + ": expected > 0");
    RestColumns columns;
    columns.width = spacing;
    for (int axis = 0; axis < 2; ++axis) {
        const LatticeAxis lattice = lattice_axis(rest, axis == 0 ? 0 : 2);
        columns.pitch[axis] = lattice.pitch > 0 ? lattice.pitch : spacing;
        columns.origin[axis] = lattice.pitch > 0 ? lattice.first - lattice.pitch / 2 : Real(0);
    }
    const int32_t n = static_cast<int32_t>(rest.size());
    std::vector<ColumnCell> cell(n);
    for (int32_t p = 0; p < n; ++p) cell[p] = columns.cell_of(rest[p].x(), rest[p].z());
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
    const Real mean =
        std::accumulate(rest_volume.begin(), rest_volume.end(), Real(0)) / rest_volume.size();
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
                               const std::vector<Vec3>& x, Real gap, const GroundBand& ground) {
    if (rest.size() != x.size())
        throw InputError("layer shape: " + std::to_string(x.size()) + " current positions for " +
                         std::to_string(rest.size()) + " rest positions");
    LayerShape shape;
    shape.columns = columns.n_columns();
    if (shape.columns == 0) return shape;
    std::vector<Real> top_rise, split_height;
    top_rise.reserve(shape.columns);
    int32_t split = 0, lifted = 0;
    for (int32_t c = 0; c < shape.columns; ++c) {
        const int32_t b = columns.begin[c], e = columns.begin[c + 1];
        const int32_t bottom = columns.particle[b], top = columns.particle[e - 1];
        top_rise.push_back(x[top].y() - rest[top].y());
        bool is_lifted = x[bottom].y() - rest[bottom].y() > gap;
        Real widest = 0, widest_height = 0;  // the widest gap above the ground band
        for (int32_t k = b + 1; k < e; ++k) {
            const int32_t lo = columns.particle[k - 1], hi = columns.particle[k];
            const Real opening = (x[hi].y() - x[lo].y()) - (rest[hi].y() - rest[lo].y());
            if (!(opening > gap)) continue;
            const Real height = x[lo].y() - ground.ground_y;
            if (height < ground.band) {
                is_lifted = true;
            } else if (opening > widest) {
                widest = opening;
                widest_height = height;
            }
        }
        if (widest > 0) {
            ++split;
            split_height.push_back(widest_height / ground.cell);
        }
        lifted += is_lifted;
    }
    shape.split_fraction = Real(split) / shape.columns;
    shape.lifted_fraction = Real(lifted) / shape.columns;
    // with no ground the heights are measured from -inf: report none
    if (std::isfinite(ground.ground_y)) {
        std::vector<Real> copy = split_height;
        shape.split_height_median = quantile(split_height, 0.5);
        shape.split_height_p10 = quantile(copy, 0.1);
    }
    shape.top_rise_median = quantile(top_rise, 0.5);
    shape.top_rise_p95 = quantile(top_rise, 0.95);
    shape.curl = shape.top_rise_p95 - shape.top_rise_median;
    return shape;
}

FragmentSizes measure_fragment_sizes(const Fragments& fragments,
                                     const std::vector<Real>& rest_volume) {
    if (fragments.id.size() != rest_volume.size())
        throw InputError("fragment sizes: " + std::to_string(fragments.id.size()) + " labels for " +
                         std::to_string(rest_volume.size()) + " particle volumes");
    FragmentSizes sizes;
    sizes.count = fragments.count;
    std::vector<Real> volume(fragments.count, 0);
    for (size_t p = 0; p < rest_volume.size(); ++p)
        if (fragments.id[p] >= 0) volume[fragments.id[p]] += rest_volume[p];
    const SizeSummary summary = summarize_sizes(volume);
    sizes.total_volume = summary.total;
    sizes.largest_fraction = summary.largest_fraction;
    sizes.weighted_mean_volume = summary.weighted_mean;
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

// The top layer (the particles within two column widths of their column's top) and its
// components through unbroken edges: root per particle (-1 off the top) and component sizes.
struct TopLayer {
    int32_t top_particles = 0;
    std::vector<int32_t> root;  // (n_particles): smallest particle of the component, or -1
    std::vector<int32_t> size;  // (n_particles): component size at its root
};

void check_edges_and_columns(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                             const RestColumns& columns, const char* what) {
    if (static_cast<int32_t>(is_broken.size()) != topo.n_edges())
        throw InputError(std::string(what) + ": " + std::to_string(is_broken.size()) +
                         " edge flags for " + std::to_string(topo.n_edges()) + " edges");
    if (static_cast<int32_t>(columns.particle.size()) != topo.n_particles)
        throw InputError(std::string(what) + ": columns hold " +
                         std::to_string(columns.particle.size()) + " particles, the mesh " +
                         std::to_string(topo.n_particles));
}

/// 1 for the particles within two column widths of their column's top.
std::vector<uint8_t> top_layer_mask(const CoreTopology& topo, const RestColumns& columns) {
    std::vector<uint8_t> on_top(topo.n_particles, 0);
    for (int32_t c = 0; c < columns.n_columns(); ++c) {
        const Real top_y = topo.X[columns.particle[columns.begin[c + 1] - 1]].y();
        for (int32_t k = columns.begin[c]; k < columns.begin[c + 1]; ++k) {
            const int32_t p = columns.particle[k];
            if (topo.X[p].y() > top_y - 2 * columns.width) on_top[p] = 1;
        }
    }
    return on_top;
}

TopLayer top_layer_components(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                              const RestColumns& columns, const char* what) {
    check_edges_and_columns(topo, is_broken, columns, what);
    TopLayer layer;
    const std::vector<uint8_t> on_top = top_layer_mask(topo, columns);
    layer.top_particles = static_cast<int32_t>(std::count(on_top.begin(), on_top.end(), 1));
    std::vector<int32_t> parent(topo.n_particles);
    std::iota(parent.begin(), parent.end(), 0);
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        if (is_broken[e] || !on_top[p] || !on_top[q]) continue;
        const int32_t a = find_root(parent, p), b = find_root(parent, q);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
    layer.root.assign(topo.n_particles, -1);
    layer.size.assign(topo.n_particles, 0);
    for (int32_t p = 0; p < topo.n_particles; ++p)
        if (on_top[p]) ++layer.size[layer.root[p] = find_root(parent, p)];
    return layer;
}

}  // namespace

std::vector<int32_t> top_polygon_labels(const CoreTopology& topo,
                                        const std::vector<uint8_t>& is_broken,
                                        const RestColumns& columns, int min_particles) {
    const TopLayer layer = top_layer_components(topo, is_broken, columns, "top polygon labels");
    const int32_t smallest = std::max(min_particles, kMinPolygonParticles);
    std::vector<int32_t> label_of_root(topo.n_particles, -1), label(topo.n_particles, -1);
    int32_t count = 0;
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        const int32_t r = layer.root[p];
        if (r < 0 || layer.size[r] < smallest) continue;
        if (label_of_root[r] < 0) label_of_root[r] = count++;
        label[p] = label_of_root[r];
    }
    return label;
}

SurfacePolygons measure_surface_polygons(const CoreTopology& topo,
                                         const std::vector<uint8_t>& is_broken,
                                         const RestColumns& columns, int min_particles) {
    const TopLayer layer = top_layer_components(topo, is_broken, columns, "surface polygons");
    SurfacePolygons polygons;
    polygons.top_particles = layer.top_particles;
    const std::vector<int32_t>& size = layer.size;
    // each top particle stands for an equal share of the footprint (columns x cell area)
    const Real particle_area =
        polygons.top_particles > 0
            ? columns.n_columns() * columns.pitch.x() * columns.pitch.y() / polygons.top_particles
            : 0;
    std::vector<Real> areas;
    for (int32_t p = 0; p < topo.n_particles; ++p)
        if (size[p] >= std::max(min_particles, kMinPolygonParticles))
            areas.push_back(size[p] * particle_area);
    polygons.count = static_cast<int32_t>(areas.size());
    const SizeSummary summary = summarize_sizes(areas);
    polygons.weighted_mean_area = summary.weighted_mean;
    polygons.largest_fraction = summary.largest_fraction;
    if (summary.weighted_mean > 0) polygons.effective_count = summary.total / summary.weighted_mean;
    return polygons;
}

UnopenedWalls measure_unopened_walls(const CoreTopology& topo,
                                     const std::vector<uint8_t>& is_broken,
                                     const std::vector<uint8_t>& is_cut, const RestColumns& columns,
                                     const std::vector<Vec3>& x, const std::vector<float>& Jw) {
    check_edges_and_columns(topo, is_broken, columns, "unopened walls");
    check_edges_and_columns(topo, is_cut, columns, "unopened walls");
    if (x.size() != static_cast<size_t>(topo.n_particles) || !(Jw.empty() || Jw.size() == x.size()))
        throw InputError("unopened walls: " + std::to_string(x.size()) + " positions and " +
                         std::to_string(Jw.size()) + " Jw for " + std::to_string(topo.n_particles) +
                         " particles");
    const std::vector<uint8_t> on_top = top_layer_mask(topo, columns);
    const auto shrink = [&](int32_t p) { return Jw.empty() ? Real(1) : std::cbrt(Real(Jw[p])); };
    UnopenedWalls walls;
    std::vector<Real> strain;
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        if (!is_cut[e] || !on_top[p] || !on_top[q]) continue;
        ++walls.wall_edges;
        if (is_broken[e]) continue;
        const Real dried_rest = (topo.X[p] - topo.X[q]).norm() * 0.5 * (shrink(p) + shrink(q));
        strain.push_back((x[p] - x[q]).norm() / dried_rest - 1);
    }
    walls.unopened_edges = static_cast<int32_t>(strain.size());
    if (walls.wall_edges > 0) walls.unopened_fraction = Real(strain.size()) / walls.wall_edges;
    if (!strain.empty()) walls.unopened_strain_median = quantile(strain, 0.5);
    return walls;
}

CrackDepth measure_crack_depth(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                               const RestColumns& columns) {
    check_edges_and_columns(topo, is_broken, columns, "crack depth");
    std::vector<uint8_t> cracked(topo.n_particles, 0);
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (is_broken[e]) cracked[topo.edges[e][0]] = cracked[topo.edges[e][1]] = 1;
    CrackDepth depth;
    std::vector<Real> depths, thickness;
    int32_t through = 0;
    for (int32_t c = 0; c < columns.n_columns(); ++c) {
        const int32_t bottom = columns.begin[c], top = columns.begin[c + 1] - 1;
        if (!cracked[columns.particle[top]]) continue;
        int32_t lowest = top;
        while (lowest > bottom && cracked[columns.particle[lowest - 1]]) --lowest;
        const Real top_y = topo.X[columns.particle[top]].y();
        depths.push_back(top_y - topo.X[columns.particle[lowest]].y());
        thickness.push_back(top_y - topo.X[columns.particle[bottom]].y());
        if (lowest == bottom) ++through;
    }
    depth.cracked_columns = static_cast<int32_t>(depths.size());
    if (depths.empty()) return depth;
    depth.cracked_fraction = Real(depth.cracked_columns) / columns.n_columns();
    depth.depth_max = *std::max_element(depths.begin(), depths.end());
    depth.depth_p90 = quantile(depths, 0.9);
    depth.depth_median = quantile(depths, 0.5);
    depth.thickness_median = quantile(thickness, 0.5);
    depth.through_fraction = Real(through) / depth.cracked_columns;
    return depth;
}

namespace {

// crack points line up where their neighbourhood's covariance has one eigenvalue this many times
// the other (a straight row of points: infinitely many; a filled disc: 1)
constexpr Real kLineAnisotropy = 4;
// crack points within this many column widths of the footprint's edge are the rim's
constexpr int64_t kRimColumns = 6;

// crack points hashed on a square grid of `cell` in x-z, for the neighbour queries
class PointGrid {
public:
    PointGrid(const std::vector<Vec2>& points, Real cell) : m_points(points), m_cell(cell) {
        for (int32_t i = 0; i < static_cast<int32_t>(points.size()); ++i)
            m_cells[key(points[i])].push_back(i);
    }
    // calls fn(j) for every point j within `radius` (<= cell) of `at`
    template <class Fn>
    void near(const Vec2& at, Real radius, Fn&& fn) const {
        const auto [cx, cz] = key(at);
        for (int64_t dx = -1; dx <= 1; ++dx)
            for (int64_t dz = -1; dz <= 1; ++dz) {
                const auto it = m_cells.find({cx + dx, cz + dz});
                if (it == m_cells.end()) continue;
                for (int32_t j : it->second)
                    if ((m_points[j] - at).squaredNorm() <= radius * radius) fn(j);
            }
    }

private:
    std::pair<int64_t, int64_t> key(const Vec2& p) const {
        return {static_cast<int64_t>(std::floor(p.x() / m_cell)),
                static_cast<int64_t>(std::floor(p.y() / m_cell))};
    }
    const std::vector<Vec2>& m_points;
    Real m_cell;
    std::map<std::pair<int64_t, int64_t>, std::vector<int32_t>> m_cells;
};

// the bin of `bins` bins of 15 degrees, each centred on a multiple of 15, that holds an angle in
// [0, 15 bins) degrees (the last half bin wraps to bin 0)
int angle_bin(Real angle_deg, int bins) {
    const int k = static_cast<int>(std::floor(angle_deg / 15 + Real(0.5)));
    return ((k % bins) + bins) % bins;
}

// angle of a direction in the x-z plane, folded to [0, 180) degrees (a line has no sign)
Real line_angle_deg(const Vec2& d) {
    Real a = std::atan2(d.y(), d.x()) * 180 / kPi;
    if (a < 0) a += 180;
    return a >= 180 ? a - 180 : a;
}

using ColumnCells = std::set<ColumnCell>;

// the footprint's column cells
ColumnCells footprint_cells(const CoreTopology& topo, const RestColumns& columns) {
    ColumnCells footprint;
    for (int32_t c = 0; c < columns.n_columns(); ++c) {
        const Vec3& r = topo.X[columns.particle[columns.begin[c]]];
        footprint.insert(columns.cell_of(r.x(), r.z()));
    }
    return footprint;
}

// a point kRimColumns or more columns inside the footprint: not on the rim
bool is_inland(const ColumnCells& footprint, const RestColumns& columns, const Vec2& at) {
    const auto [cx, cz] = columns.cell_of(at.x(), at.y());
    for (int64_t dx = -kRimColumns; dx <= kRimColumns; ++dx)
        for (int64_t dz = -kRimColumns; dz <= kRimColumns; ++dz)
            if (!footprint.count({cx + dx, cz + dz})) return false;
    return true;
}

// The standard error of the aligned share over the cracks it is drawn from: `crack` holds each
// crack's aligned and oriented length; the share is resampled kBootstrapResamples times by
// drawing as many cracks with replacement (mt19937_64 from a fixed seed, whose output the standard
// fixes bit for bit, reduced by our own modulo: the same figure with any standard library)
Real crack_bootstrap_stderr(const std::vector<std::pair<Real, Real>>& crack) {
    constexpr int kBootstrapResamples = 1000;
    const uint64_t n = crack.size();
    if (n < 2) return 0;
    std::mt19937_64 rng(0x5eed);
    Real sum = 0, sum_sq = 0;
    for (int r = 0; r < kBootstrapResamples; ++r) {
        Real aligned = 0, oriented = 0;
        for (uint64_t k = 0; k < n; ++k) {
            const auto& [a, o] = crack[rng() % n];
            aligned += a, oriented += o;
        }
        const Real share = aligned / oriented;
        sum += share, sum_sq += share * share;
    }
    const Real mean = sum / kBootstrapResamples;
    return std::sqrt(std::max(Real(0), sum_sq / kBootstrapResamples - mean * mean));
}

// local direction: the principal axis of the crack points around each inland one, where they
// line up (an isotropic cloud, the rubble of a wide crack band or a junction, has no direction:
// an eigen solver would hand back a coordinate axis for it); sets oriented_points, the oriented
// length, axis_aligned_fraction and its standard error over the cracks (`pair`: each point's
// crack). Each oriented point stands for 2 radius / n of crack length, n the crack points within
// `radius` of it: a straight crack through the disc's centre is 2 radius long there whatever its
// points' spacing, and that spacing depends on the crack's direction (on a lattice's Kuhn tets a
// vertical plane crosses 1.8 times as many edges a metre square to a face diagonal as along it),
// so counting points would weigh the directions unequally.
void measure_crack_directions(const std::vector<Vec2>& point,
                              const std::vector<std::pair<int32_t, int32_t>>& pair,
                              const PointGrid& grid, Real radius, const ColumnCells& footprint,
                              const RestColumns& columns, CrackNetwork& net) {
    int32_t oriented = 0;
    Real aligned_length = 0;
    Vec2 square_sum = Vec2::Zero();  // sum of length (cos 4 theta, sin 4 theta)
    std::map<std::pair<int32_t, int32_t>, std::pair<Real, Real>> by_crack;
    for (size_t i = 0; i < point.size(); ++i) {
        const Vec2& at = point[i];
        if (!is_inland(footprint, columns, at)) continue;
        Vec2 mean = Vec2::Zero();
        int n = 0;
        grid.near(at, radius, [&](int32_t j) { mean += point[j], ++n; });
        mean /= n;
        Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
        grid.near(at, radius, [&](int32_t j) {
            const Vec2 d = point[j] - mean;
            cov += d * d.transpose();
        });
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
        if (!(eig.eigenvalues()(1) >= kLineAnisotropy * eig.eigenvalues()(0))) continue;
        ++oriented;
        const Real length = 2 * radius / n;
        const Real angle = line_angle_deg(eig.eigenvectors().col(1));  // the larger eigenvalue's
        const Real off_axis = std::min({angle, std::abs(angle - 90), 180 - angle});
        const Real aligned = off_axis <= 15 ? length : Real(0);
        aligned_length += aligned;
        net.oriented_length += length;
        auto& [crack_aligned, crack_oriented] = by_crack[pair[i]];
        crack_aligned += aligned, crack_oriented += length;
        net.direction_histogram[angle_bin(angle, kCrackDirectionBins)] += length;
        const Real four_theta = 4 * angle * kPi / 180;
        square_sum += length * Vec2(std::cos(four_theta), std::sin(four_theta));
    }
    net.oriented_points = oriented;
    if (net.oriented_length > 0) {
        net.axis_aligned_fraction = aligned_length / net.oriented_length;
        net.square_order = square_sum.norm() / net.oriented_length;
        net.square_phase_deg = std::atan2(square_sum.y(), square_sum.x()) * 180 / kPi / 4;
    }
    std::vector<std::pair<Real, Real>> crack;
    crack.reserve(by_crack.size());
    for (const auto& [key, lengths] : by_crack) crack.push_back(lengths);
    net.oriented_cracks = static_cast<int32_t>(crack.size());
    net.axis_aligned_fraction_stderr = crack_bootstrap_stderr(crack);
}

// The crack points of one polygon pair near a junction, as offsets from its centre. Its
// direction is the line through them (their principal axis), pointed away from the centre: the
// mean offset alone leans toward wherever the centre sits off the crack line.
struct Branch {
    Vec2 sum = Vec2::Zero();
    Eigen::Matrix2d moment = Eigen::Matrix2d::Zero();
    int count = 0;

    void add(const Vec2& offset) { sum += offset, moment += offset * offset.transpose(), ++count; }
    Vec2 mean() const { return sum / count; }
    Vec2 direction() const {
        const Vec2 m = mean();
        const Eigen::Matrix2d cov = moment / count - m * m.transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
        // too few points, or a blob rather than a line: the mean's direction
        if (count < 3 || !(eig.eigenvalues()(1) >= kLineAnisotropy * eig.eigenvalues()(0)))
            return m;
        const Vec2 axis = eig.eigenvectors().col(1);
        return axis.dot(m) >= 0 ? axis : Vec2(-axis);
    }
};

// junctions: clusters of crack points with three or more polygons among their neighbours'
// pairs, each a T or a Y by its branches' widest gap; sets junctions, t_fraction and y_fraction
void classify_junctions(const std::vector<Vec2>& point,
                        const std::vector<std::pair<int32_t, int32_t>>& pair, const PointGrid& grid,
                        Real junction_radius, Real branch_radius, Real w, CrackNetwork& net) {
    // junction candidates, clustered greedily in index order (deterministic)
    std::vector<uint8_t> is_candidate(point.size(), 0);
    for (size_t i = 0; i < point.size(); ++i) {
        std::vector<int32_t> polygons;
        grid.near(point[i], junction_radius, [&](int32_t j) {
            if (pair[j].first == pair[j].second) return;
            polygons.push_back(pair[j].first);
            polygons.push_back(pair[j].second);
        });
        std::sort(polygons.begin(), polygons.end());
        is_candidate[i] = std::unique(polygons.begin(), polygons.end()) - polygons.begin() >= 3;
    }
    // a junction: a connected cluster of candidates (neighbours within the junction radius)
    std::vector<uint8_t> is_taken(point.size(), 0);
    int32_t t_count = 0, y_count = 0, branched = 0, right_angles = 0, gap_count = 0;
    for (size_t i = 0; i < point.size(); ++i) {
        if (!is_candidate[i] || is_taken[i]) continue;
        std::vector<int32_t> cluster = {static_cast<int32_t>(i)};
        is_taken[i] = 1;
        for (size_t k = 0; k < cluster.size(); ++k)
            grid.near(point[cluster[k]], junction_radius, [&](int32_t j) {
                if (!is_candidate[j] || is_taken[j]) return;
                is_taken[j] = 1;
                cluster.push_back(j);
            });
        Vec2 center = Vec2::Zero();
        for (int32_t j : cluster) center += point[j];
        center /= static_cast<Real>(cluster.size());
        ++net.junctions;
        // a branch per polygon pair near the junction, along its crack points (Branch)
        std::map<std::pair<int32_t, int32_t>, Branch> branches;
        grid.near(center, branch_radius, [&](int32_t j) {
            // inside a polygon: not a branch between two
            if (pair[j].first == pair[j].second) return;
            branches[pair[j]].add(point[j] - center);
        });
        std::vector<Real> angles;
        for (const auto& [key, branch] : branches) {
            // a pair whose points sit on the junction: no direction
            if (branch.mean().norm() < w / 2) continue;
            const Vec2 d = branch.direction();
            angles.push_back(std::atan2(d.y(), d.x()) * 180 / kPi);
        }
        if (angles.size() < 3) continue;
        ++branched;
        std::sort(angles.begin(), angles.end());
        // the angles between neighbouring branches, the last one across the cut at +-180
        std::vector<Real> gaps = {angles.front() + 360 - angles.back()};
        for (size_t k = 1; k < angles.size(); ++k) gaps.push_back(angles[k] - angles[k - 1]);
        for (Real gap : gaps) {
            ++net.junction_angle_histogram[angle_bin(gap, kJunctionAngleBins)];
            right_angles += std::abs(gap - 90) <= 15;
        }
        gap_count += static_cast<int32_t>(gaps.size());
        const Real widest = *std::max_element(gaps.begin(), gaps.end());
        if (widest >= 150)
            ++t_count;
        else if (angles.size() == 3)
            ++y_count;
    }
    if (branched > 0) {
        net.t_fraction = Real(t_count) / branched;
        net.y_fraction = Real(y_count) / branched;
        net.junction_right_angle_fraction = Real(right_angles) / gap_count;
    }
}

}  // namespace

CrackNetwork measure_crack_network(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                   const RestColumns& columns, int min_particles) {
    const std::vector<int32_t> label = top_polygon_labels(topo, is_broken, columns, min_particles);
    // crack points: rest midpoints (x, z) of broken edges between two polygon particles, with the
    // polygon pair (equal for a crack that has not yet cut its polygon in two)
    std::vector<Vec2> point;
    std::vector<std::pair<int32_t, int32_t>> pair;
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        if (!is_broken[e]) continue;
        const auto [p, q] = topo.edges[e];
        const int32_t a = label[p], b = label[q];
        if (a < 0 || b < 0) continue;
        const Vec3 m = (topo.X[p] + topo.X[q]) / 2;
        point.emplace_back(m.x(), m.z());
        pair.emplace_back(std::min(a, b), std::max(a, b));
    }
    CrackNetwork net;
    net.crack_points = static_cast<int32_t>(point.size());
    if (point.empty()) return net;
    const Real w = columns.width;
    const Real direction_radius = 4 * w, junction_radius = 2 * w, branch_radius = 4 * w;
    const PointGrid grid(point, branch_radius);
    // the rim is left out of the directions: cracks along the slab's own edges follow its
    // outline, not the grid, and a box's outline runs along the grid axes
    measure_crack_directions(point, pair, grid, direction_radius, footprint_cells(topo, columns),
                             columns, net);
    classify_junctions(point, pair, grid, junction_radius, branch_radius, w, net);
    return net;
}

PolygonSides measure_polygon_sides(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                   const RestColumns& columns, int min_particles) {
    constexpr Real kPlateShare = 0.01;
    constexpr int32_t kMinSideColumns = 3;
    const std::vector<int32_t> label = top_polygon_labels(topo, is_broken, columns, min_particles);
    // each column's cell and the polygon of its top particle (-1: a crumb's, or none)
    using Cell = ColumnCell;
    std::map<Cell, int32_t> region;
    std::map<int32_t, int32_t> columns_of;
    int32_t labelled = 0;
    for (int32_t c = 0; c < columns.n_columns(); ++c) {
        const Vec3& r = topo.X[columns.particle[columns.begin[c]]];
        const int32_t top = label[columns.particle[columns.begin[c + 1] - 1]];
        region[columns.cell_of(r.x(), r.z())] = top;
        if (top >= 0) ++columns_of[top], ++labelled;
    }
    // plates seed a breadth-first fill of the other columns, in cell order (deterministic)
    std::vector<Cell> queue;
    for (auto& [cell, r] : region) {
        if (r >= 0 && columns_of[r] < kPlateShare * labelled) r = -1;
        if (r >= 0) queue.push_back(cell);
    }
    const Cell steps[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (size_t i = 0; i < queue.size(); ++i)
        for (const Cell& d : steps) {
            const auto it = region.find({queue[i].first + d.first, queue[i].second + d.second});
            if (it == region.end() || it->second >= 0) continue;
            it->second = region[queue[i]];
            queue.push_back(it->first);
        }
    // the columns two plates share a border along, and the plates whose columns reach the
    // footprint's edge (a column with a side open to the air)
    std::map<std::pair<int32_t, int32_t>, int32_t> border;
    std::set<int32_t> on_rim, plates;
    for (const auto& [cell, r] : region) {
        if (r < 0) continue;
        plates.insert(r);
        for (const Cell& d : steps)
            if (!region.count({cell.first + d.first, cell.second + d.second})) on_rim.insert(r);
        for (const Cell& d : {Cell{1, 0}, Cell{0, 1}}) {
            const auto it = region.find({cell.first + d.first, cell.second + d.second});
            if (it != region.end() && it->second >= 0 && it->second != r)
                ++border[{std::min(r, it->second), std::max(r, it->second)}];
        }
    }
    std::map<int32_t, int32_t> sides;
    for (const auto& [pair, length] : border)
        if (length >= kMinSideColumns) ++sides[pair.first], ++sides[pair.second];
    PolygonSides result;
    int64_t total = 0;
    for (int32_t plate : plates) {
        if (on_rim.count(plate)) continue;
        const int32_t n = sides[plate];
        ++result.inland_plates, total += n;
        ++result.histogram[std::min(n, kPolygonSidesBins - 1)];
    }
    if (result.inland_plates > 0) result.mean_sides = Real(total) / result.inland_plates;
    return result;
}

CrackPace measure_crack_pace(const std::vector<int32_t>& first_break, int frame_start,
                             int frame_end, int last) {
    // broken edges by the frame they first broke in, frames start..last
    const int frames = last - frame_start + 1;
    CrackPace pace;
    if (frames <= 0) return pace;
    std::vector<int64_t> new_breaks(frames, 0);
    for (int32_t f : first_break)
        if (f <= last) ++new_breaks[std::max(f, frame_start) - frame_start];
    const int64_t total = std::accumulate(new_breaks.begin(), new_breaks.end(), int64_t(0));
    if (total == 0) return pace;
    int64_t so_far = 0;
    for (int k = 0; k < frames; ++k) {
        if (new_breaks[k] > 0 && pace.first_crack_frame < 0)
            pace.first_crack_frame = frame_start + k;
        so_far += new_breaks[k];
        if (2 * so_far >= total) {
            pace.half_broken_frame = frame_start + k;
            break;
        }
    }
    if (frame_end > frame_start)
        pace.half_broken_range_fraction =
            Real(pace.half_broken_frame - frame_start) / Real(frame_end - frame_start);
    return pace;
}

HardeningHalves measure_hardening_halves(const std::vector<int32_t>& surface,
                                         const std::vector<float>& alpha, Real alpha0) {
    HardeningHalves halves;
    halves.surface_particles = static_cast<int32_t>(surface.size());
    if (surface.empty()) return halves;
    int32_t compressed = 0, stretched = 0;
    const float a0 = static_cast<float>(alpha0);
    for (int32_t p : surface) {
        if (p < 0 || static_cast<size_t>(p) >= alpha.size())
            throw InputError("hardening halves: surface particle " + std::to_string(p) + " of " +
                             std::to_string(alpha.size()));
        compressed += alpha[p] < a0;
        stretched += alpha[p] > a0;
    }
    halves.compressed_fraction = Real(compressed) / surface.size();
    halves.stretched_fraction = Real(stretched) / surface.size();
    return halves;
}

}  // namespace mudcrack
