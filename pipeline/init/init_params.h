#pragma once
/// What mc-init builds the particles from, and how finely. Paths are absolute
/// (resolved against the shot file by pipeline/shot).
#include <optional>
#include <string>

#include "sim/core/error.h"
#include "sim/core/types.h"
#include "sim/material/strength_field.h"

namespace mudcrack {

enum class SourceType { Mesh, Box, Heightfield };
/// How a box is filled: a lattice split into Kuhn tets (regular, or its interior points
/// jittered), or CGAL Mesh_3's tets of the box's surface, as a mesh source is filled, whose
/// edges run every way (the lattice's run along three axes and their diagonals, and cracks follow
/// them: docs/physics.md §6.6).
enum class Lattice { Regular, Jittered, Mesh };

/// A box lattice's footprint in XZ: the whole rectangle, or the ellipse inscribed in it (a round
/// puddle when the box is square), whose rim points sit on the ellipse.
enum class Footprint { Rectangle, Ellipse };

struct MeshSource {
    std::string path;               // closed triangle mesh (OBJ, PLY, STL, OFF, glTF)
    Real scale = 1;                 // uniform scale applied after loading
    Vec3 translate = Vec3::Zero();  // applied after scaling [m]
    bool fit_to_ground = true;      // translate so the lowest point sits on y = 0 (after translate)
};

/// A box slab filled with a lattice split into 6 tets per cell (Kuhn/Freudenthal split), so the
/// particle count is exactly prod(n_i + 1); or, with Lattice::Mesh, tetrahedralized by Mesh_3 at
/// InitParams::edge_length (or default_edge_length(h)), spacing and jitter unused.
struct BoxSource {
    Vec3 min = Vec3(-0.5, 0, -0.5);  // [m]
    Vec3 max = Vec3(0.5, 0.1, 0.5);  // [m]
    Real spacing = 0.025;            // lattice spacing [m]
    Lattice lattice = Lattice::Regular;
    Real jitter = 0.25;  // jitter amplitude in units of spacing (interior only)
    Footprint footprint = Footprint::Rectangle;
};

/// How a heightfield is filled: its lattice of columns (each column's points spread evenly from
/// the bottom to its top, in rows along x and z), or CGAL Mesh_3's tets of its closed surface,
/// whose edges run every way (docs/physics.md §6.6).
enum class HeightfieldLattice { Columns, Mesh };

/// A terrain slab: flat bottom at y = 0, top at base + a carved channel and gentle noise, or
/// a grayscale PNG heightmap.
struct HeightfieldSource {
    Vec3 size = Vec3(4, 0, 4);   // x and z extent [m] (y ignored)
    Real base = 0.3;             // thickness at the banks [m]
    Real amplitude = 0.05;       // bank undulation amplitude [m]
    Real channel_depth = 0.15;   // depth of the carved channel [m]
    Real channel_width = 0.8;    // channel width [m]
    Real channel_meander = 0.5;  // lateral meander amplitude [m]
    std::string image;           // optional grayscale PNG; overrides the formula
    Real image_height = 0.3;     // height of a white pixel [m]
    Real spacing = 0.05;         // column spacing [m]: the lattice's, or the surface's samples
    HeightfieldLattice lattice = HeightfieldLattice::Columns;
};

/// A shot value the builders refuse, as "<pointer> = <value>: <expectation>": they see the values,
/// not the shot file, so mc-init puts the file's name in front and the message reads like every
/// other bad-input error (docs/architecture.md §5).
class ShotValueError : public InputError {
public:
    using InputError::InputError;
};

struct InitParams {
    SourceType type = SourceType::Box;
    MeshSource mesh;
    BoxSource box;
    HeightfieldSource heightfield;
    Real edge_length = 0;  // target tet edge length for CGAL Mesh_3 [m]; 0 = derived from h
    unsigned seed = 1;     // jitter, mesher and strength-field seed
    std::optional<StrengthFieldParams> strength_field;  // p0 multipliers cached per particle
};

}  // namespace mudcrack

namespace mudcrack {
/// "mesh" | "box" | "heightfield" (inline: the shot library names sources without linking the
/// CGAL init target).
inline const char* source_type_name(SourceType type) {
    switch (type) {
        case SourceType::Mesh: return "mesh";
        case SourceType::Box: return "box";
        case SourceType::Heightfield: return "heightfield";
    }
    return "?";
}
}  // namespace mudcrack
