#pragma once
/// Particle files as OpenVDB PointDataGrids (Houdini-native, Blosc-compressed): mc-init's
/// particles.vdb and mc-sim's per-frame caches. Attribute names follow the standard ones where they
/// exist (P, v, id); metadata carries mudcrack:format_version, mudcrack:stage, mudcrack:frame.
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sim/core/particle_frame.h"
#include "sim/core/types.h"

namespace mudcrack {

constexpr int kPointsFormatVersion = 1;

/// A point cloud with named attributes, in particle-id order (id[i] is usually i).
struct PointCloud {
    std::vector<Vec3f> P;                                            // positions [m]
    std::vector<int32_t> id;                                         // particle ids
    std::vector<std::pair<std::string, std::vector<float>>> floats;  // scalar attributes
    std::vector<std::pair<std::string, std::vector<Vec3f>>> vec3s;   // vector attributes
    std::vector<std::pair<std::string, std::vector<Mat3f>>> mat3s;   // matrix attributes
    std::map<std::string, std::string> meta_string;                  // e.g. mudcrack:stage
    std::map<std::string, double> meta_double;                       // e.g. mudcrack:time
    // e.g. mudcrack:frame, mudcrack:format_version
    std::map<std::string, int64_t> meta_int;

    const std::vector<float>* find_float(const std::string& name) const;
    const std::vector<Vec3f>* find_vec3(const std::string& name) const;
    const std::vector<Mat3f>* find_mat3(const std::string& name) const;
};

/// Writes `cloud` as one PointDataGrid named "particles" with the given voxel size [m] (the sim's h
/// is a good choice). Atomic: written to a temporary name and renamed. Sets
/// mudcrack:format_version and mudcrack:point_count (int64).
/// @note Encoding: P vec3s (NullCodec: full float precision), id int32, floats "float", Vec3f
/// "vec3s", Mat3f "mat3s" (openvdb::math::Mat3s, element (i,j) = M(i,j); Houdini's VDB-to-points
/// conversion makes it a matrix3 attribute, transposed to Houdini's row-vector convention), all
/// NullCodec. Empty `id` means ids 0..n-1. Identical clouds give byte-identical files (the
/// header UUID is derived from the content).
void write_points(const std::filesystem::path& path, const PointCloud& cloud, double voxel_size);

/// Reads a file written by write_points, reordered by ascending id. Throws InputError naming the
/// file when it is missing, truncated, not a mudcrack points file, or of another format version.
PointCloud read_points(const std::filesystem::path& path);

/// Reads only the metadata (cheap: no attribute data).
PointCloud read_points_metadata(const std::filesystem::path& path);

/// A simulation frame <-> its cache: P, id, and the attributes present in `frame` (those of
/// MC_CACHED_ATTRIBUTES, under their VDB names); metadata mudcrack:frame, mudcrack:time,
/// mudcrack:substeps, mudcrack:stage = "sim".
PointCloud frame_to_points(const ParticleFrame& frame);
/// Inverse of frame_to_points. Throws InputError (naming `source`) if ids are not 0..n-1.
ParticleFrame points_to_frame(const PointCloud& cloud, const std::string& source);

/// The last frame a four-digit frame name holds (name.9999.ext): frame 10000 would get five
/// digits, sort before frame 2 and miss the "####" pattern DCCs read sequences with. The shot
/// loader refuses /frames past it.
constexpr int kMaxFrame = 9999;

/// "dir/particles.0042.vdb" style frame file names: 1-based, zero-padded to 4 digits.
std::filesystem::path frame_path(const std::filesystem::path& dir, const std::string& stem,
                                 int frame, const std::string& ext);

}  // namespace mudcrack
