#pragma once
/// Measures of what drying did to a layer of soil, from particle positions alone: how much the
/// top surface curls up, where the layer split horizontally (a peeling crust) or lifted off the
/// ground, and how big the fragments are. They turn the paper's visual claims (Fig. 6: curl and
/// fragment size grow with eps; Fig. 8: NACC alone cracks only vertically, the full model curls)
/// into numbers a test can check and a README can quote.
///
/// The layer is cut into vertical columns on its rest positions (cells in x-z of one particle
/// spacing, or of the lattice's pitch when the particles stand on one); inside a column the
/// particles keep their rest order from bottom to top. Vertical cracks separate columns sideways
/// and leave each column's stack intact, while a horizontal crack opens a gap inside a column: that
/// is what tells the two apart, with no need for crack-face normals (which on a jittered tet mesh
/// point every way).
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "sim/core/types.h"
#include "surfacing/core_topology.h"
#include "surfacing/fragments.h"

namespace mudcrack {

/// The x-z cell of a column: a pair of bin indices.
using ColumnCell = std::pair<int64_t, int64_t>;

/// Particles grouped in vertical columns of their rest positions, each sorted by rest height.
struct RestColumns {
    Real width = 0;  // particle spacing [m]: the scale of the top layer's depth and of the radii
    // the cells' pitch in x and z [m] and their corner: the lattice's pitch with each lattice
    // column at a cell's centre when the particles stand in columns of a lattice, else the
    // spacing from 0
    Vec2 pitch = Vec2::Zero();
    Vec2 origin = Vec2::Zero();
    std::vector<int32_t> begin;     // CSR offsets into particle, (n_columns + 1)
    std::vector<int32_t> particle;  // particle ids, bottom to top within a column
    int32_t n_columns() const { return static_cast<int32_t>(begin.size()) - 1; }
    /// The cell of the rest point (x, z).
    ColumnCell cell_of(Real x, Real z) const {
        return {static_cast<int64_t>(std::floor((x - origin.x()) / pitch.x())),
                static_cast<int64_t>(std::floor((z - origin.y()) / pitch.y()))};
    }
};

/// Bins rest positions into columns (> 0 spacing [m]). Along an axis whose rest coordinates take
/// few, evenly spaced values (a heightfield's columns, a regular box lattice) the cells follow
/// that lattice, one column per lattice column whatever the layers' height: a heightfield's
/// volume-based spacing is below its pitch (thinner layers), and cells of that spacing left
/// every few cells empty, which read as holes in the footprint. Elsewhere (a jittered lattice, a
/// meshed body) the cells are `spacing` wide from 0. Deterministic: columns are ordered by
/// (x, z) cell, particles within a column by rest height, then id.
RestColumns build_rest_columns(const std::vector<Vec3>& rest, Real spacing);

/// The particle spacing of a particle set: the edge of a cube of the mean particle volume (a box
/// lattice's spacing; below a heightfield's pitch, whose layers are thinner).
Real particle_spacing(const std::vector<Real>& rest_volume);

struct LayerShape {
    int32_t columns = 0;           // columns with at least one particle
    Real top_rise_median = 0;      // median vertical displacement of the columns' top particles [m]
    Real top_rise_p95 = 0;         // its 95th percentile [m]
    Real curl = 0;                 // top_rise_p95 - top_rise_median: how far the highest 5 % of the
                                   // top surface (curled rims) rose above the typical surface [m]
    Real split_fraction = 0;       // fraction of columns with a gap inside (a horizontal crack)
                                   // above the ground band
    Real lifted_fraction = 0;      // fraction of columns whose bottom rose off its rest height, or
                                   // that opened a gap inside the ground band
    Real split_height_median = 0;  // median height above the ground of the split columns' widest
                                   // gap (its lower particle), in cells of GroundBand::cell [-]
    Real split_height_p10 = 0;     // its 10th percentile [-]
};

/// Where a gap is lift-off rather than a peeling crack. A sticky (or frictional) ground holds the
/// particles whose stencil reaches its nodes, about 1.5 cells deep: a gap right above them is the
/// slab tearing off what the grid glued, which a render shows as lift-off, not as a crust peeling
/// off wetter soil.
struct GroundBand {
    Real ground_y = -std::numeric_limits<Real>::infinity();  // the ground's height [m]; -inf: none
    Real band = 0;  // gaps whose lower particle lies within this of the ground are lift-off [m]
    Real cell = 1;  // grid spacing h: split heights are reported in cells [m]
};

/// Measures the current positions `x` against the rest positions `rest` (same ids). A column is
/// split where two particles adjacent in rest order moved apart vertically by more than
/// `gap` [m] beyond their rest distance, above the ground band, and lifted where its bottom
/// particle rose more than `gap` [m] or such a gap opened inside the band. One particle spacing is
/// a natural gap: shrinkage only brings particles closer.
LayerShape measure_layer_shape(const RestColumns& columns, const std::vector<Vec3>& rest,
                               const std::vector<Vec3>& x, Real gap, const GroundBand& ground = {});

struct FragmentSizes {
    int32_t count = 0;              // fragments kept by the surfacing
    Real total_volume = 0;          // rest volume of the kept fragments [m^3]
    Real largest_fraction = 0;      // the largest fragment's share of total_volume
    Real weighted_mean_volume = 0;  // sum V_f^2 / sum V_f [m^3]: the size of the fragment a random
                                    // bit of soil belongs to, insensitive to crumbs
};

/// Fragment sizes from the surfacing's labels and the particles' rest volumes.
FragmentSizes measure_fragment_sizes(const Fragments& fragments,
                                     const std::vector<Real>& rest_volume);

/// The crack polygons of the top surface: what an artist sees from above. Desiccation cracks
/// often stop short of the bottom, so a slab cut into polygons on top is still one fragment;
/// these count the pieces of the top layer (the particles within two column widths of their
/// column's top) joined by unbroken edges.
struct SurfacePolygons {
    int32_t count = 0;          // polygons of at least min_particles top particles
    int32_t top_particles = 0;  // particles in the top layer
    Real weighted_mean_area =
        0;  // sum A^2 / sum A over polygons [m^2]; a polygon's area A is its
            // share of the top particles times the footprint (columns x width^2)
    Real largest_fraction = 0;  // the largest polygon's share of the counted top particles
    // (sum A)^2 / sum A^2: N for N equal polygons, while chips cut off along a torn band add almost
    // nothing (a top that is one plate and 16 chips of 0.5 % each: 1.2); the plates a viewer sees
    Real effective_count = 0;
};

/// `is_broken` per edge of `topo` (1 = broken at the frame measured). Polygons with fewer than
/// min_particles particles are crumbs: left out of count and areas.
SurfacePolygons measure_surface_polygons(const CoreTopology& topo,
                                         const std::vector<uint8_t>& is_broken,
                                         const RestColumns& columns, int min_particles);

/// The top layer's polygon of each particle: -1 off the top layer or in a crumb, else a label in
/// [0, count) (the polygons measure_surface_polygons counts, in order of their smallest particle).
std::vector<int32_t> top_polygon_labels(const CoreTopology& topo,
                                        const std::vector<uint8_t>& is_broken,
                                        const RestColumns& columns, int min_particles);

/// Where the plates meshes part the top and the top did not open. The plates mode (surfacing's
/// shot fracture) parts two plates wherever a band of broken edges separates them, and cuts the
/// band where it opened most; a band whose breaks lie below the top, or are scattered through it,
/// is cut across top-layer edges that never broke. Those walls close a polygon that the broken
/// edges leave joined: the count by broken edges and the count by the meshes differ by them.
struct UnopenedWalls {
    int32_t wall_edges = 0;      // top-layer edges the plates mode cuts
    int32_t unopened_edges = 0;  // of those, the edges that never broke
    Real unopened_fraction = 0;  // unopened_edges / wall_edges
    /// Median over the unopened edges of their length over their dried rest length (the rest
    /// length times the mean Jw^(1/3) of their ends, which uniformly dried soil keeps), minus 1:
    /// near 0 where the top holds as if no crack ran under it.
    Real unopened_strain_median = 0;
};

/// `is_broken` and `is_cut` per edge of `topo` at one frame, `x` the particles' positions then and
/// `Jw` their pore deformation (empty: no moisture, Jw = 1).
UnopenedWalls measure_unopened_walls(const CoreTopology& topo,
                                     const std::vector<uint8_t>& is_broken,
                                     const std::vector<uint8_t>& is_cut, const RestColumns& columns,
                                     const std::vector<Vec3>& x, const std::vector<float>& Jw);

/// Bins of CrackNetwork's histograms: 15 degrees each, over a line's directions and around a
/// junction.
constexpr int kCrackDirectionBins = 12;
constexpr int kJunctionAngleBins = 24;

/// The look of the crack network on the top surface, seen from above (in rest positions: the
/// pattern as it is drawn, not as it opened). A crack point is the rest midpoint of a broken edge
/// between two particles of top-layer polygons (the same polygon's, for a crack that has not cut
/// it in two yet).
struct CrackNetwork {
    int32_t crack_points = 0;
    /// Crack points whose neighbours (within four column widths) line up: the principal axis of
    /// their positions has at least 4 times the variance of the other. Wide bands of broken
    /// edges and junctions have no direction and are left out, and so is the rim (within six
    /// column widths of the footprint's edge): cracks there follow the slab's outline, which for
    /// a box runs along the grid axes whatever the cracks inside do.
    int32_t oriented_points = 0;
    /// The crack length the oriented points stand for [m, rest]: each point 2 r / n of it, n the
    /// crack points within r (four column widths) of it. A crack's points lie closer together
    /// in some directions than in others (on a lattice's Kuhn tets up to 1.8 times), so a count
    /// of points is not a length.
    Real oriented_length = 0;
    /// Share of the oriented crack length whose local direction lies within 15 degrees of the x or
    /// z axis (the grid's). An isotropic network gives 1/3; cracks that draw the grid, near 1.
    Real axis_aligned_fraction = 0;
    /// The cracks the oriented points belong to (a crack: the points between one pair of
    /// polygons, or inside one polygon it has not yet cut in two). A crack's points share its
    /// direction, so the share above is a sample of this many cracks, not of its points.
    int32_t oriented_cracks = 0;
    /// The share's standard error over those cracks: the spread of the share over 1,000
    /// resamplings of the cracks with replacement (a bootstrap; fixed seed, so the same network
    /// gives the same figure). 0 for a single crack. The cracks inside one polygon that have not
    /// yet cut it count as one, so a network that has not closed (a shot's first cracks) reads
    /// as a few cracks with too small an error. A few long cracks give a wide error; a
    /// share two or more of these over 1/3 is more than the chance of which cracks the network
    /// drew (treating its cracks as independent draws).
    Real axis_aligned_fraction_stderr = 0;
    /// The network's right-angle order: |<exp(4 i theta)>| over the oriented length, theta each
    /// point's direction. 0 when no pair of perpendicular directions is preferred (an isotropic
    /// network, or hexagons); 1 when every crack runs along one such pair. Drying mud, whose later
    /// cracks meet earlier ones near 90 degrees, has order: the demo's networks read 0.04-0.31
    /// (docs/physics.md §6.5).
    Real square_order = 0;
    /// The direction of that pair [degrees, in (-45, 45], from x toward z]: arg <exp(4 i theta)>
    /// / 4. The axis share is about 1/3 + 0.55 square_order cos(4 square_phase) (the 4 theta
    /// term of the directions' distribution, integrated over the axes' 15-degree windows), so a
    /// network with order 0.2 reads 22 to 44 % on the axes as its phase goes from 45 to 0. A
    /// method whose grid draws the cracks puts the phase near 0 on every seed; one that does not
    /// puts it anywhere, seed by seed.
    Real square_phase_deg = 0;
    /// Junctions: places where three or more polygons meet. Each is classified by the angles
    /// between its crack branches (the directions to the mean crack point of each polygon pair
    /// within four column widths): T when the widest angle is >= 150 degrees (a crack that ended
    /// on another), Y when three branches all lie < 150 degrees apart (cracks that split).
    int32_t junctions = 0;
    Real t_fraction = 0;  // of the junctions with three or more branches
    Real y_fraction = 0;  // of the junctions with exactly three branches, and the widest < 150 deg
    /// The oriented crack length by direction [m, rest]: bin k holds the length whose direction
    /// lies within 7.5 degrees of 15 k degrees from the x axis toward z (bin 0 takes both 0 and
    /// 180); the bins sum to oriented_length. Bins 0 and 6 are the grid's axes; a network with no
    /// preferred direction fills the bins alike.
    std::array<Real, kCrackDirectionBins> direction_histogram{};
    /// The angles between neighbouring branches, around each junction with three or more: bin k
    /// counts the angles within 7.5 degrees of 15 k degrees. A T is 90, 90 and 180; a Y of
    /// cracks that split evenly, 120 three times.
    std::array<int32_t, kJunctionAngleBins> junction_angle_histogram{};
    /// Share of those angles within 15 degrees of a right angle: where a later crack meets an
    /// earlier one, drying mud makes about 90 degrees (Bohn, Douady and Couder 2005).
    Real junction_right_angle_fraction = 0;
};

/// The crack network of the top layer at the frame `is_broken` describes.
CrackNetwork measure_crack_network(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                   const RestColumns& columns, int min_particles);

/// Bins of PolygonSides' histogram: bin k counts plates of k sides, the last that many or more.
constexpr int kPolygonSidesBins = 10;

/// How many sides the top's plates have, as drying mud's polygons are counted (Bohn, Douady and
/// Couder 2005: mostly four-sided, 4 to 5 on average). A plate is a top polygon holding at least
/// 1 % of the top's labelled columns (chips and crumbs are not polygons of the network). Every
/// other column of the footprint goes to the nearest plate across the top (a wide band of crumbs
/// is split down its middle), and a plate's sides are the other plates it borders along at least
/// 3 columns (a corner where four meet is no side). Only plates whose columns do not reach the
/// footprint's edge count: the others have the slab's outline for a side.
struct PolygonSides {
    int32_t inland_plates = 0;
    Real mean_sides = 0;  // over the inland plates
    std::array<int32_t, kPolygonSidesBins> histogram{};
};

/// The sides of the top's plates at the frame `is_broken` describes.
PolygonSides measure_polygon_sides(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                   const RestColumns& columns, int min_particles);

/// When the cracks appear, from the frame each edge first broke (BreakHistory::first_break, never
/// broken edges past any frame): frames up to `last` count.
struct CrackPace {
    int first_crack_frame = -1;  // the first frame with a broken edge; -1 if none by `last`
    /// The first frame by which half of frame `last`'s broken edges exist; -1 if none
    int half_broken_frame = -1;
    /// Where half_broken_frame falls in the shot's frame range: 0 at its start, 1 at its end
    Real half_broken_range_fraction = 0;
};

/// The pace of a shot whose frames run from `frame_start` to `frame_end`, measured up to `last`.
CrackPace measure_crack_pace(const std::vector<int32_t>& first_break, int frame_start,
                             int frame_end, int last);

/// How deep cracks that open the top surface reach down (in rest positions). A column is cracked
/// at the top when its top particle has a broken edge; its crack depth is the rest height of the
/// top particle minus that of the lowest particle of the unbroken run of cracked particles (each
/// with a broken edge) that starts at the top. So a scratch on the top particle alone is 0 deep,
/// a crack down to the base is the column's thickness, and a peeling crust's horizontal crack
/// counts as deep as the vertical crack that reaches it.
struct CrackDepth {
    int32_t cracked_columns = 0;  // columns cracked at the top
    Real cracked_fraction = 0;    // their share of the columns
    Real depth_median = 0;        // median crack depth of the cracked columns [m]
    Real depth_p90 = 0;           // its 90th percentile [m]
    Real depth_max = 0;           // [m]
    // median rest thickness (top - bottom particle) of the cracked columns [m]
    Real thickness_median = 0;
    Real through_fraction = 0;  // cracked columns whose crack reaches their bottom particle
};

/// The crack depth of the layer at the frame `is_broken` describes.
CrackDepth measure_crack_depth(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                               const RestColumns& columns);

/// The surface particles in each half of the hardening colormap (render/colormap.h: blue below
/// alpha0, red above): hardened ("compressed", alpha < alpha0) and softened ("stretched",
/// alpha > alpha0), as fractions of the surface particles.
struct HardeningHalves {
    int32_t surface_particles = 0;
    Real compressed_fraction = 0;
    Real stretched_fraction = 0;
};

/// `surface` lists the particles on the boundary (each once), `alpha` is per particle.
HardeningHalves measure_hardening_halves(const std::vector<int32_t>& surface,
                                         const std::vector<float>& alpha, Real alpha0);

}  // namespace mudcrack
