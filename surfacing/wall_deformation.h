#pragma once
/// The smoothed motion of the particles along the crack walls (plates mode, docs/physics.md §5.7).
///
/// A wall's points and its rim on the skin follow their owner particles (Eq. 13 without Jw), and
/// the particles of a torn band move unevenly at the scale of their spacing: the rim of a plate
/// that was a smooth curve in the rest state becomes a saw-tooth where it is. Here each particle
/// that owns a point of a wall moves instead by the affine map fitted (weighted least squares, as
/// moving least squares does) to the motion of the particles around it on its own side of every
/// crack: within `radius` in the rest state and reached from it without crossing an edge the
/// last frame cuts. The neighbourhoods are fixed for the shot, so the smoothed motion is as
/// continuous in time as the particles are, and a wall still follows only its own side.
///
/// While a band tears, its particles part unevenly by up to a cell a frame, and the fitted motion
/// of a particle beside it swings as fast: a rim that follows it would jump beyond its particles.
/// So in a sequence the fit eases in as a fresh crack does (FrameCores::opening): from the frame
/// of a particle's first cut, its motion blends from its own to the fitted one over the cut's
/// easing frames, by the time its band has mostly torn. And a particle that tore loose from its
/// neighbourhood's motion, which the fit would carry centimetres, is carried at most max_lead:
/// the fit smooths the rims' teeth at the particle spacing, not the particles' own paths.
#include <cstdint>
#include <vector>

#include "sim/core/particle_frame.h"
#include "sim/core/types.h"
#include "surfacing/core_topology.h"

namespace mudcrack {

/// The wall particles and their neighbourhoods, from the rest state and the last frame's cuts.
struct WallDeformation {
    std::vector<int32_t> particle;   // particles that own a point of a last-frame wall, ascending
    std::vector<int32_t> first_cut;  // the frame of the first cut among the walls each one owns
                                     // a point of (ShotFracture::cut_frame)
    std::vector<int32_t> begin;      // CSR offsets of each one's neighbours, (particle.size() + 1)
    std::vector<int32_t> neighbour;  // neighbour particle ids (the particle itself included)
    std::vector<float> weight;       // their weights (Gaussian in rest distance, sigma radius / 2)
    std::vector<Vec3> rest_centre;   // weighted mean rest position of each neighbourhood
    std::vector<Mat3> rest_inverse;  // inverse of its weighted rest covariance (zero: not fitted)
    Real max_lead = 0;    // [m] the farthest the fit carries a point of a core from its own motion
    Real core_reach = 0;  // [m] how far a core's rest points lie from its particle (half a spacing)

    bool empty() const { return particle.empty(); }
    size_t memory_bytes() const;
};

/// The neighbourhoods of the particles that own a point of a wall through the edges with
/// is_cut[e] != 0, cut from frame cut_frame[e]: particles within `radius` [m] of each in the rest
/// state, joined to it through
/// uncut edges, of the same piece (piece[p]; kDebris particles are neither smoothed nor used).
/// A neighbourhood too small or too flat to fit an affine map (fewer than 6 particles, or a rest
/// covariance whose least principal variance is under 2 % of its largest) keeps its particle's
/// own motion. `max_lead` [m] (> 0) bounds how far the fit carries a core's points from their
/// particle's own motion. Deterministic.
WallDeformation plan_wall_deformation(const CoreTopology& topo, const std::vector<uint8_t>& is_cut,
                                      const std::vector<int32_t>& cut_frame,
                                      const std::vector<int32_t>& piece, Real radius,
                                      Real max_lead);

/// The smoothed motion of the wall particles in `frame`: x[p] and A[p] such that a rest point y0
/// of p's core goes to x[p] + A[p] (y0 - X_p), A the fitted affine map's linear part. Only the
/// wall particles of `deformation` that were fitted are written. On entry x and A hold each
/// particle's own motion; it moves by own + w s (fit - own), where s <= 1 scales the fit's lead
/// |dx| + |dA|_F core_reach down to max_lead, and with ease_frames > 0 a particle first cut at
/// frame c eases in by w = (frame - c) / ease_frames clamped to [0, 1] (else w = 1).
void smooth_wall_motion(const CoreTopology& topo, const WallDeformation& deformation,
                        const ParticleFrame& frame, int ease_frames, std::vector<Vec3>& x,
                        std::vector<Mat3>& A);

}  // namespace mudcrack
