#pragma once
/// The heightfield terrain source: a riverbed slab with a flat bottom at y = 0 and a top from a
/// formula (banks with a gentle undulation, a meandering carved channel) or a grayscale PNG.
#include "pipeline/init/init_params.h"
#include "pipeline/io/mesh_io.h"
#include "sim/core/tet_mesh.h"

namespace mudcrack {

/// Top height of the riverbed formula at (x, z) [m]; the slab spans x in [-size.x/2, size.x/2]
/// and z in [-size.z/2, size.z/2]. The channel runs along x; its centre line meanders as
/// z_c(x) = channel_meander * sin(2 pi x / size.x) (one full bend across the slab) and its
/// cross-section is a cosine bowl: depth * (1 + cos(2 pi d / width)) / 2 for |d| < width / 2,
/// d = z - z_c(x). The banks undulate by at most `amplitude` with two fixed sinusoids.
Real riverbed_height(const HeightfieldSource& hf, Real x, Real z);

/// The terrain as a column-mapped lattice (x and z regular at ~spacing, each column's points
/// spread evenly from y = 0 to the top, as many layers as the tallest column needs), split
/// into Kuhn tets, all positive. With `image` set, the PNG covers the slab (top row at
/// z = -size.z/2, left column at x = -size.x/2), sampled bilinearly; gray 255 is image_height,
/// and columns thinner than a quarter of the spacing are raised to that (a warning counts them)
/// so black pixels keep a thin floor instead of degenerate tets.
/// Throws InputError naming the /source/heightfield keys when the formula cuts through the
/// floor (channel_depth + amplitude >= base) or the image cannot be read.
TetMesh make_heightfield_tets(const HeightfieldSource& hf);

/// The terrain's closed surface, for Mesh_3 to fill (HeightfieldLattice::Mesh): the top sampled on
/// the same columns as make_heightfield_tets (~spacing apart, from the formula or the image), a
/// flat bottom at y = 0 and four vertical walls, two triangles per quad, outward and
/// counter-clockwise. Throws as make_heightfield_tets does, except that the layer count (a
/// lattice's) is not checked: Mesh_3's edge length sets the particle count.
InputSurface heightfield_surface(const HeightfieldSource& hf);

}  // namespace mudcrack
