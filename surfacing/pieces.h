#pragma once
/// Pieces of the plates surfacing (docs/physics.md §5.7): the soil split into plates with one
/// crack between neighbouring plates, instead of a band of particle-sized chips.
///
/// MPM smears a crack over two to three cells, and the stretch test of Eq. 14 breaks every edge
/// in that band, so every band particle becomes a fragment of its own, and the particles along
/// the band keep torn edges that leave slivers of wall inside the soil. Here the soil no crack
/// touched (the particles without a broken edge, joined through their edges) makes the plates,
/// those at least `min_width` across; every other particle (the band) joins the plate it moved
/// with: the one it reaches along the path that opened least (the sum over the path's edges of
/// how much longer than at rest they are this frame), so the cut runs where the band actually
/// opened. A band particle that every path reaches only through more than `debris_gap` of
/// opening has torn loose: it is debris, not meshed.
#include <cstdint>
#include <vector>

#include "sim/core/particle_frame.h"
#include "sim/core/types.h"
#include "surfacing/core_topology.h"

namespace mudcrack {

struct PieceParams {
    Real min_width = 0;     // [m] a fragment this wide (piece_width) or wider is a plate
    Real debris_gap = 0.5;  // [particle spacings] a band particle whose every path to a plate
                            // opened more than this is debris
};

/// The piece a particle belongs to when it belongs to none.
constexpr int32_t kDebris = -1;

struct Pieces {
    /// Piece of each particle: the smallest particle id of its plate, so an id stays the same
    /// from frame to frame until a crack splits the plate; kDebris for debris. (n_particles)
    std::vector<int32_t> id;
    /// The plate particle each particle hangs from (itself for a plate particle); for debris, the
    /// plate particle it was torn from (nearest through the rest mesh), or -1 without plates.
    std::vector<int32_t> root;
    /// Per edge: the surface separates its two particles (a crack wall runs through it).
    std::vector<uint8_t> is_cut;
    int32_t count = 0;   // pieces
    int32_t debris = 0;  // debris particles
};

/// How wide a set of rest points is across: the second-largest principal width
/// sqrt(12 lambda_2 + a^2) of their covariance (a uniform slab of width w has variance w^2 / 12),
/// with `spacing` a (one particle's width) added, so a plate of any thickness is as wide as its
/// smaller in-plane side and a sliver or a column of particles is as wide as it is thick.
/// @param sum, sum_outer the sum of the points and of their outer products, @param count points
Real piece_width(const Vec3& sum, const Mat3& sum_outer, int64_t count, Real spacing);

/// The mean particle spacing of a rest mesh: the cube root of its mean rest volume per particle.
Real mean_particle_spacing(const CoreTopology& topo);

/// Splits frame `frame` into pieces. `is_broken` is Eq. 14's broken state at this frame
/// (edge_breaks.h). Deterministic: depends only on its arguments.
///
/// An edge is cut when its particles are in different pieces or either is debris. Inside one
/// piece (a crack that ends inside a plate, or one whose sides still join below it) a broken edge
/// is cut when its ends hang from plate particles on two sides of that crack: plate particles
/// that no path of three plate edges joins. So each band has one wall, where its two sides meet,
/// and the torn edges on either side are welded.
Pieces find_pieces(const CoreTopology& topo, const ParticleFrame& frame,
                   const std::vector<uint8_t>& is_broken, const PieceParams& params);

}  // namespace mudcrack
