#pragma once
/// Measures of what drying did to a layer of soil, from particle positions alone: how much the
/// top surface curls up, where the layer split horizontally (a peeling crust) or lifted off the
/// ground, and how big the fragments are. They turn the paper's visual claims (Fig. 6: curl and
/// fragment size grow with eps; Fig. 8: NACC alone cracks only vertically, the full model curls)
/// into numbers a test can check and a README can quote.
///
/// The layer is cut into vertical columns on its rest positions (a square grid in x-z of one
/// particle spacing); inside a column the particles keep their rest order from bottom to top.
/// Vertical cracks separate columns sideways and leave each column's stack intact, while a
/// horizontal crack opens a gap inside a column: that is what tells the two apart, with no need
/// for crack-face normals (which on a jittered tet mesh point every way).
#include <cstdint>
#include <vector>

#include "sim/core/types.h"
#include "surfacing/core_topology.h"
#include "surfacing/fragments.h"

namespace mudcrack {

/// Particles grouped in vertical columns of their rest positions, each sorted by rest height.
struct RestColumns {
    Real width = 0;                           // column width [m] (x and z)
    std::vector<int32_t> begin;               // CSR offsets into particle, (n_columns + 1)
    std::vector<int32_t> particle;            // particle ids, bottom to top within a column
    int32_t n_columns() const { return static_cast<int32_t>(begin.size()) - 1; }
};

/// Bins rest positions into columns of the given width [m] (> 0). Deterministic: columns are
/// ordered by (x, z) cell, particles within a column by rest height, then id.
RestColumns build_rest_columns(const std::vector<Vec3>& rest, Real width);

/// The column width for a particle set: the edge of a cube of the mean particle volume
/// (the lattice spacing for box and heightfield sources).
Real particle_spacing(const std::vector<Real>& rest_volume);

struct LayerShape {
    int32_t columns = 0;          // columns with at least one particle
    Real top_rise_median = 0;     // median vertical displacement of the columns' top particles [m]
    Real top_rise_p95 = 0;        // its 95th percentile [m]
    Real curl = 0;                // top_rise_p95 - top_rise_median: how far the highest 5 % of the
                                  // top surface (curled rims) rose above the typical surface [m]
    Real split_fraction = 0;      // fraction of columns with a gap inside (a horizontal crack)
    Real lifted_fraction = 0;     // fraction of columns whose bottom rose off its rest height
};

/// Measures the current positions `x` against the rest positions `rest` (same ids). A column is
/// split where two particles adjacent in rest order moved apart vertically by more than
/// `gap` [m] beyond their rest distance, and lifted where its bottom particle rose more than
/// `gap` [m]. One particle spacing is a natural gap: shrinkage only brings particles closer.
LayerShape measure_layer_shape(const RestColumns& columns, const std::vector<Vec3>& rest,
                               const std::vector<Vec3>& x, Real gap);

struct FragmentSizes {
    int32_t count = 0;             // fragments kept by the surfacing
    Real total_volume = 0;         // rest volume of the kept fragments [m^3]
    Real largest_fraction = 0;     // the largest fragment's share of total_volume
    Real weighted_mean_volume = 0; // sum V_f^2 / sum V_f [m^3]: the size of the fragment a random
                                   // bit of soil belongs to, insensitive to crumbs
};

/// Fragment sizes from the surfacing's labels and the particles' rest volumes.
FragmentSizes measure_fragment_sizes(const Fragments& fragments, const std::vector<Real>& rest_volume);

/// The crack polygons of the top surface: what an artist sees from above. Desiccation cracks
/// often stop short of the bottom, so a slab cut into polygons on top is still one fragment;
/// these count the pieces of the top layer (the particles within two column widths of their
/// column's top) joined by unbroken edges.
struct SurfacePolygons {
    int32_t count = 0;             // polygons of at least min_particles top particles
    int32_t top_particles = 0;     // particles in the top layer
    Real weighted_mean_area = 0;   // sum A^2 / sum A over polygons [m^2]; a polygon's area A is its
                                   // share of the top particles times the footprint (columns x width^2)
    Real largest_fraction = 0;     // the largest polygon's share of the counted top particles
};

/// `is_broken` per edge of `topo` (1 = broken at the frame measured). Polygons with fewer than
/// min_particles particles are crumbs: left out of count and areas.
SurfacePolygons measure_surface_polygons(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                                         const RestColumns& columns, int min_particles);

}  // namespace mudcrack
