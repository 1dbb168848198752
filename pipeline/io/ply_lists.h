#pragma once
// A walk over a PLY file's body checking its list counts before assimp reads it.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mudcrack {

/// A PLY scalar type: its size, and for integers the largest value (a list's largest count).
struct PlyType {
    size_t bytes = 0;  // 0: a name PLY does not have
    bool is_signed = false;
    bool is_float = false;
    uint64_t max = 0;  // the largest count an integer type holds
};

/// The type a PLY header names ("uchar", "int32", "float64", ...); bytes = 0 for an unknown name.
PlyType ply_type(const std::string& name);

/// One property of a PLY element, as its header line declares it.
struct PlyProperty {
    bool is_list = false;
    std::string count_type;  // list only
    std::string type;        // the scalar's or the list items' type
};

/// One element of a PLY header: its name, instance count and properties in order.
struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// assimp 5.2.5 sizes a list by the count the file states, before reading its items and without
/// checking the count against the count's type (an ASCII "uchar" count of 666666667 asked for
/// 5 GB; found by tests/fuzz). This walks the body from byte `body_offset` in the header's order,
/// as assimp does (ASCII: one instance per line, numbers parsed as assimp parses them; binary:
/// exact), and throws InputError naming the file, the element and the instance when a list count
/// is negative, larger than its type holds, or larger than the bytes left in the file.
/// `format` is "ascii", "binary_little_endian" or "binary_big_endian".
void check_ply_list_counts(const std::filesystem::path& path, uint64_t body_offset,
                           const std::string& format, const std::vector<PlyElement>& elements);

}  // namespace mudcrack
