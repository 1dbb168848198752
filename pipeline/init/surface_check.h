#pragma once
/// Checks that an input surface bounds a solid Mesh_3 can fill: closed, manifold, consistently
/// and outward oriented, free of self-intersections. Refusals name the file, the problem, how
/// often it occurs and where the first occurrence is.
#include <string>
#include <vector>

#include "pipeline/io/mesh_io.h"
#include "sim/core/types.h"

namespace mudcrack {

/// The combinatorial problems of a triangle soup, one message per kind, each starting with
/// `name` (the file): faces with a repeated vertex, border edges (not closed), edges shared by
/// more than two faces, edges whose two faces disagree on orientation, and vertices whose faces
/// form several fans (non-manifold vertices, checked only when the edges are fine).
/// Empty when the surface is a closed, oriented 2-manifold. CGAL-free (surface_topology.cpp).
std::vector<std::string> surface_topology_problems(const InputSurface& surface,
                                                   const std::string& name);

/// The full check: surface_topology_problems, then with CGAL Polygon_mesh_processing the
/// self-intersections and the enclosed volume, which must be positive (outward normals).
/// Throws InputError listing every problem found, one per line, e.g.
/// "bunny.obj: 12 border edges (the mesh is not closed), first at (0.1, 0.2, 0.3)".
/// @return the enclosed volume [m^3]. Implemented in cgal_surface.cpp.
Real check_input_surface(const InputSurface& surface, const std::string& name);

/// Signed volume enclosed by a closed triangle soup (divergence theorem) [m^3]: positive when
/// the faces wind counter-clockwise seen from outside.
Real enclosed_volume(const InputSurface& surface);

}  // namespace mudcrack
