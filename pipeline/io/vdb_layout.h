#pragma once
// A byte-level check of a points cache's OpenVDB layout, run before OpenVDB parses the file.
#include <cstdint>
#include <filesystem>
#include <string>

namespace mudcrack {

/// What a points cache's grids must be: the tree type its descriptor names and the transform
/// its grid stores (the only kinds mudcrack writes).
struct VdbLayoutExpectation {
    std::string tree_type;          // e.g. "Tree_ptdataidx32_5_4_3"
    std::string map_type;           // e.g. "UniformScaleMap"
    uint32_t map_bytes = 0;         // that map's stored size
    uint32_t root_value_bytes = 0;  // the tree's value size (a root tile's value)
};

/// OpenVDB 10 trusts the file it reads: it allocates what a stored string length or metadata
/// size asks for, reads a metadata or root-tile bool as a raw byte (a byte other than 0 or 1 is
/// undefined behaviour), and reads the last leaf without noticing that the file's final bytes are
/// missing; and its zip and blosc readers allocate the byte count a node's value block states, or
/// read that many raw bytes into the node's buffer before comparing with its size (a heap
/// overflow). This walks what OpenVDB reads before the leaf buffers: the header, the file
/// metadata, each grid descriptor (its tree type, its end offset inside the file), the grid's
/// metadata, transform, root node and internal nodes of a 5-4-3 tree (masks, value blocks), and
/// throws InputError naming the file and the first fault.
void check_vdb_layout(const std::filesystem::path& path, const VdbLayoutExpectation& expected);

}  // namespace mudcrack
