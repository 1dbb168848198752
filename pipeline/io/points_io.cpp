#include "pipeline/io/points_io.h"

#include <openvdb/openvdb.h>
#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/PointIndexGrid.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <numeric>
#include <system_error>
#include <type_traits>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/checksum.h"
#include "pipeline/io/vdb_layout.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;
namespace vdbp = openvdb::points;

namespace mudcrack {

namespace {

// the on-disk layout (documented for Houdini users and the lead):
//   one PointDataGrid named "particles", linear transform with voxel size = write_points'
//   voxel_size; P     vec3s, NullCodec (full float precision), world position id    int32 float
//   attributes -> "float", Vec3f -> "vec3s", Mat3f -> "mat3s" (openvdb::math::Mat3s, element
//         (i,j) = M(i,j); Houdini's VDB-to-points conversion turns it into a matrix3 attribute,
//         transposed to Houdini's row-vector convention), all NullCodec
//   grid metadata: the cloud's string/double/int64 entries + mudcrack:format_version (int64) and
//         mudcrack:point_count (int64); creator "mudcrack <version>"
constexpr const char* kGridName = "particles";
constexpr const char* kFormatVersionKey = "mudcrack:format_version";
constexpr const char* kPointCountKey = "mudcrack:point_count";

void initialize_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

// metadata that OpenVDB itself maintains on every grid: not the cloud's business
bool is_openvdb_managed_meta(const std::string& name) {
    return name == openvdb::GridBase::META_GRID_CLASS ||
           name == openvdb::GridBase::META_GRID_CREATOR ||
           name == openvdb::GridBase::META_GRID_NAME ||
           name == openvdb::GridBase::META_SAVE_HALF_FLOAT ||
           name == openvdb::GridBase::META_IS_LOCAL_SPACE ||
           name == openvdb::GridBase::META_VECTOR_TYPE || name.rfind("file_", 0) == 0;
}

openvdb::Vec3f to_vdb(const Vec3f& v) { return openvdb::Vec3f(v.x(), v.y(), v.z()); }
Vec3f from_vdb(const openvdb::Vec3f& v) { return Vec3f(v.x(), v.y(), v.z()); }
openvdb::math::Mat3s to_vdb(const Mat3f& m) {
    return openvdb::math::Mat3s(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0),
                                m(2, 1), m(2, 2));
}
Mat3f from_vdb(const openvdb::math::Mat3s& m) {
    Mat3f out;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out(i, j) = m(i, j);
    return out;
}

template <class T>
void check_attribute_size(const fs::path& path, const std::string& name,
                          const std::vector<T>& values, size_t n) {
    if (values.size() != n) {
        throw RuntimeError(path.string() + ": attribute '" + name + "' has " +
                           std::to_string(values.size()) + " values for " + std::to_string(n) +
                           " points");
    }
}

// appends one NullCodec attribute and fills it in the point order of `index_tree`
template <class VdbT, class T, class Convert>
void add_attribute(vdbp::PointDataTree& tree, const openvdb::tools::PointIndexTree& index_tree,
                   const std::string& name, const std::vector<T>& values, Convert convert) {
    std::vector<VdbT> converted(values.size());
    std::transform(values.begin(), values.end(), converted.begin(), convert);
    vdbp::appendAttribute<VdbT, vdbp::NullCodec>(tree, name);
    vdbp::populateAttribute(tree, index_tree, name, vdbp::PointAttributeVector<VdbT>(converted));
}

openvdb::points::PointDataGrid::Ptr make_grid(const fs::path& path, const PointCloud& cloud,
                                              double voxel_size) {
    const size_t n = cloud.P.size();
    if (!(voxel_size > 0) || !std::isfinite(voxel_size)) {
        throw RuntimeError(path.string() + ": voxel size " + std::to_string(voxel_size) +
                           " must be finite and > 0 [m]");
    }
    if (!cloud.id.empty()) check_attribute_size(path, "id", cloud.id, n);
    // index-space coordinates must fit OpenVDB's int32 voxel coordinates
    const double max_index = double(1 << 30);
    std::vector<openvdb::Vec3f> positions(n);
    for (size_t i = 0; i < n; ++i) {
        const Vec3f& p = cloud.P[i];
        if (!p.allFinite() || p.cwiseAbs().maxCoeff() / voxel_size > max_index) {
            throw RuntimeError(path.string() + ": point " + std::to_string(i) + " has position (" +
                               std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
                               std::to_string(p.z()) + "): not finite or too far for voxel size " +
                               std::to_string(voxel_size));
        }
        positions[i] = to_vdb(p);
    }

    // bucket the points into voxels, then store P relative to each voxel at full float precision
    const auto transform = openvdb::math::Transform::createLinearTransform(voxel_size);
    const vdbp::PointAttributeVector<openvdb::Vec3f> position_wrapper(positions);
    const auto index_grid = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(
        position_wrapper, *transform);
    auto grid = vdbp::createPointDataGrid<vdbp::NullCodec, vdbp::PointDataGrid>(
        *index_grid, position_wrapper, *transform);
    grid->setName(kGridName);
    grid->setCreator(std::string("mudcrack ") + MUDCRACK_VERSION);

    // attributes, in the cloud's order (the file's attribute order follows it)
    auto& tree = grid->tree();
    const auto& index_tree = index_grid->tree();
    std::vector<int32_t> ids = cloud.id;
    if (ids.empty()) {
        ids.resize(n);
        std::iota(ids.begin(), ids.end(), 0);
    }
    if (n > 0) {
        add_attribute<int32_t>(tree, index_tree, "id", ids, [](int32_t v) { return v; });
        for (const auto& [name, values] : cloud.floats) {
            check_attribute_size(path, name, values, n);
            add_attribute<float>(tree, index_tree, name, values, [](float v) { return v; });
        }
        for (const auto& [name, values] : cloud.vec3s) {
            check_attribute_size(path, name, values, n);
            add_attribute<openvdb::Vec3f>(tree, index_tree, name, values,
                                          [](const Vec3f& v) { return to_vdb(v); });
        }
        for (const auto& [name, values] : cloud.mat3s) {
            check_attribute_size(path, name, values, n);
            add_attribute<openvdb::math::Mat3s>(tree, index_tree, name, values,
                                                [](const Mat3f& m) { return to_vdb(m); });
        }
    }

    // metadata: the cloud's, then ours (which win)
    for (const auto& [key, value] : cloud.meta_string)
        grid->insertMeta(key, openvdb::StringMetadata(value));
    for (const auto& [key, value] : cloud.meta_double)
        grid->insertMeta(key, openvdb::DoubleMetadata(value));
    for (const auto& [key, value] : cloud.meta_int)
        grid->insertMeta(key, openvdb::Int64Metadata(value));
    grid->insertMeta(kFormatVersionKey, openvdb::Int64Metadata(kPointsFormatVersion));
    grid->insertMeta(kPointCountKey, openvdb::Int64Metadata(int64_t(n)));
    return grid;
}

// The VDB file header holds a random 36-character UUID (OpenVDB's Archive::writeHeader) right
// after magic (8 bytes), file version (4), library version (4+4) and the grid-offsets flag (1).
// Replacing it by a UUID derived from the rest of the file makes identical clouds give
// byte-identical files, which make's reruns and our determinism checks rely on.
constexpr std::streamoff kUuidOffset = 21;
constexpr size_t kUuidLength = 36;

bool looks_like_uuid(const std::string& s) {
    if (s.size() != kUuidLength) return false;
    for (size_t i = 0; i < s.size(); ++i) {
        const bool is_dash_slot = i == 8 || i == 13 || i == 18 || i == 23;
        if (is_dash_slot ? s[i] != '-' : !std::isxdigit(static_cast<unsigned char>(s[i])))
            return false;
    }
    return true;
}

void make_uuid_content_derived(const fs::path& file) {
    std::fstream io(file, std::ios::in | std::ios::out | std::ios::binary);
    std::string uuid(kUuidLength, '\0');
    io.seekg(kUuidOffset);
    io.read(uuid.data(), std::streamsize(kUuidLength));
    if (!io || !looks_like_uuid(uuid)) {
        throw RuntimeError(file.string() + ": unexpected VDB header layout (no UUID at byte " +
                           std::to_string(kUuidOffset) + "): cannot make the file deterministic");
    }
    // hash everything after the UUID
    uint64_t h1 = kFnv1a64Offset;
    std::vector<char> chunk(1 << 20);
    while (io.read(chunk.data(), std::streamsize(chunk.size())) || io.gcount() > 0) {
        h1 = fnv1a64(chunk.data(), size_t(io.gcount()), h1);
    }
    const uint64_t h2 = fnv1a64(&h1, sizeof h1, h1 ^ 0x9e3779b97f4a7c15ull);
    // RFC 9562 version 8 ("custom") layout: xxxxxxxx-xxxx-8xxx-yxxx-xxxxxxxxxxxx
    char text[kUuidLength + 1];
    std::snprintf(text, sizeof text, "%08x-%04x-8%03x-%04x-%012llx", unsigned(h1 >> 32),
                  unsigned((h1 >> 16) & 0xffff), unsigned(h1 & 0xfff),
                  unsigned(0x8000 | ((h2 >> 48) & 0x3fff)),
                  static_cast<unsigned long long>(h2 & 0xffffffffffffull));
    io.clear();
    io.seekp(kUuidOffset);
    io.write(text, std::streamsize(kUuidLength));
    io.close();
    if (!io) throw RuntimeError(file.string() + ": cannot rewrite the VDB header UUID");
}

// openvdb::io::File::write (OpenVDB 10) opens its own std::ofstream and never checks it after
// writing, so a full disk leaves a truncated file without an error. This writer hands OpenVDB's
// archive a stream we own and check; the bytes are the same as File::write's (seekable layout).
class CheckedVdbWriter : public openvdb::io::Archive {
public:
    void write_to(std::ostream& os, const openvdb::GridCPtrVec& grids) const {
        Archive::write(os, grids, /*seekable=*/true);
    }
};

// opens the file and returns the "particles" grid, data or metadata only; every failure names the
// file
openvdb::GridBase::Ptr open_particles_grid(const fs::path& path, bool metadata_only) {
    initialize_openvdb();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw InputError(path.string() +
                         ": points file not found (expected a mudcrack OpenVDB "
                         "points cache)");
    }
    // ScaleMap and UniformScaleMap store five Vec3d: scale, voxel size, inverse scale, its square
    // and half the inverse scale
    check_vdb_layout(
        path,
        {vdbp::PointDataGrid::gridType(), openvdb::math::UniformScaleMap::mapType(),
         uint32_t(5 * sizeof(openvdb::Vec3d)), uint32_t(sizeof(vdbp::PointDataTree::ValueType))});
    openvdb::GridBase::Ptr grid;
    try {
        openvdb::io::File file(path.string());
        file.open(/*delayLoad=*/false);
        if (!file.hasGrid(kGridName)) {
            throw InputError(path.string() + ": not a mudcrack points file: no grid named '" +
                             kGridName + "'");
        }
        grid = metadata_only ? file.readGridMetadata(kGridName) : file.readGrid(kGridName);
        file.close();
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path.string() +
                         ": cannot read the points file (truncated or not an "
                         "OpenVDB file?): " +
                         e.what());
    }
    // the format version decides whether we understand the rest
    const auto version = grid->getMetadata<openvdb::Int64Metadata>(kFormatVersionKey);
    if (!version) {
        throw InputError(path.string() + ": not a mudcrack points file: grid '" + kGridName +
                         "' has no int64 metadata '" + kFormatVersionKey + "'");
    }
    if (version->value() != kPointsFormatVersion) {
        throw InputError(path.string() + ": " + kFormatVersionKey + " = " +
                         std::to_string(version->value()) + ": this build reads version " +
                         std::to_string(kPointsFormatVersion) + " only");
    }
    if (!metadata_only && !grid->isType<vdbp::PointDataGrid>()) {
        throw InputError(path.string() + ": grid '" + kGridName + "' is a " + grid->type() +
                         ", expected a PointDataGrid");
    }
    return grid;
}

PointCloud metadata_of(const openvdb::GridBase& grid) {
    PointCloud cloud;
    for (auto it = grid.beginMeta(); it != grid.endMeta(); ++it) {
        const std::string& key = it->first;
        if (is_openvdb_managed_meta(key)) continue;
        const openvdb::Metadata& meta = *it->second;
        if (auto s = dynamic_cast<const openvdb::StringMetadata*>(&meta))
            cloud.meta_string[key] = s->value();
        else if (auto d = dynamic_cast<const openvdb::DoubleMetadata*>(&meta))
            cloud.meta_double[key] = d->value();
        else if (auto f = dynamic_cast<const openvdb::FloatMetadata*>(&meta))
            cloud.meta_double[key] = f->value();
        else if (auto l = dynamic_cast<const openvdb::Int64Metadata*>(&meta))
            cloud.meta_int[key] = l->value();
        else if (auto i = dynamic_cast<const openvdb::Int32Metadata*>(&meta))
            cloud.meta_int[key] = i->value();
    }
    return cloud;
}

// reads attribute `pos` of every point in leaf order into `out`, converted by `convert`
template <class VdbT, class T, class Convert>
void gather(const vdbp::PointDataTree& tree, size_t pos, std::vector<T>& out, Convert convert) {
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const vdbp::AttributeHandle<VdbT> handle(leaf->constAttributeArray(pos));
        for (auto idx = leaf->beginIndexOn(); idx; ++idx) out.push_back(convert(handle.get(*idx)));
    }
}

template <class T>
std::vector<T> permuted(const std::vector<T>& values, const std::vector<size_t>& order) {
    std::vector<T> out(order.size());
    for (size_t i = 0; i < order.size(); ++i) out[i] = values[order[i]];
    return out;
}

// the cloud's attribute list for elements of type T (float, Vec3f or Mat3f)
template <class T>
auto& attributes_of(PointCloud& cloud) {
    if constexpr (std::is_same_v<T, float>)
        return cloud.floats;
    else if constexpr (std::is_same_v<T, Vec3f>)
        return cloud.vec3s;
    else
        return cloud.mat3s;
}

template <class T>
const std::vector<T>* find_attribute(const PointCloud& cloud, const std::string& name) {
    if constexpr (std::is_same_v<T, float>)
        return cloud.find_float(name);
    else if constexpr (std::is_same_v<T, Vec3f>)
        return cloud.find_vec3(name);
    else
        return cloud.find_mat3(name);
}

}  // namespace

const std::vector<float>* PointCloud::find_float(const std::string& name) const {
    for (const auto& [n, values] : floats)
        if (n == name) return &values;
    return nullptr;
}
const std::vector<Vec3f>* PointCloud::find_vec3(const std::string& name) const {
    for (const auto& [n, values] : vec3s)
        if (n == name) return &values;
    return nullptr;
}
const std::vector<Mat3f>* PointCloud::find_mat3(const std::string& name) const {
    for (const auto& [n, values] : mat3s)
        if (n == name) return &values;
    return nullptr;
}

void write_points(const fs::path& path, const PointCloud& cloud, double voxel_size) {
    initialize_openvdb();
    const auto grid = make_grid(path, cloud, voxel_size);
    write_atomically(path, [&](const fs::path& tmp) {
        errno = 0;
        std::ofstream os(tmp, std::ios::out | std::ios::binary | std::ios::trunc);
        if (!os)
            throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
        try {
            CheckedVdbWriter().write_to(os, openvdb::GridCPtrVec{grid});
        } catch (const openvdb::Exception& e) {
            throw RuntimeError(tmp.string() + ": cannot write the points file: " + e.what());
        }
        os.close();
        if (!os)
            throw RuntimeError(tmp.string() +
                               ": cannot write the points file: " + write_error_reason());
        make_uuid_content_derived(tmp);
    });
}

PointCloud read_points_metadata(const fs::path& path) {
    return metadata_of(*open_particles_grid(path, /*metadata_only=*/true));
}

PointCloud read_points(const fs::path& path) {
    const auto base = open_particles_grid(path, /*metadata_only=*/false);
    const auto grid = openvdb::gridPtrCast<vdbp::PointDataGrid>(base);
    PointCloud cloud = metadata_of(*grid);
    const auto& tree = grid->tree();
    const size_t n = size_t(vdbp::pointCount(tree));
    const auto stored_count = cloud.meta_int.find(kPointCountKey);
    if (stored_count != cloud.meta_int.end() && stored_count->second != int64_t(n)) {
        throw InputError(path.string() + ": holds " + std::to_string(n) + " points but " +
                         kPointCountKey + " = " + std::to_string(stored_count->second));
    }
    if (n == 0) return cloud;

    // the attribute layout, in the order the attributes were appended
    const auto& descriptor = tree.cbeginLeaf()->attributeSet().descriptor();
    std::vector<std::string> names(descriptor.size());
    for (const auto& [name, pos] : descriptor.map()) names[pos] = name;
    if (descriptor.find("id") == vdbp::AttributeSet::INVALID_POS ||
        descriptor.valueType(descriptor.find("id")) != openvdb::typeNameAsString<int32_t>()) {
        throw InputError(path.string() + ": not a mudcrack points file: no int32 attribute 'id'");
    }

    // world positions: the voxel's index coordinate plus the stored in-voxel offset
    std::vector<Vec3f> P;
    P.reserve(n);
    const openvdb::math::Transform& transform = grid->transform();
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const vdbp::AttributeHandle<openvdb::Vec3f> handle(leaf->constAttributeArray("P"));
        for (auto idx = leaf->beginIndexOn(); idx; ++idx) {
            const openvdb::Vec3d offset = handle.get(*idx);
            const openvdb::Vec3d world = transform.indexToWorld(offset + idx.getCoord().asVec3d());
            P.emplace_back(float(world.x()), float(world.y()), float(world.z()));
        }
    }
    std::vector<int32_t> ids;
    ids.reserve(n);
    gather<int32_t>(tree, descriptor.find("id"), ids, [](int32_t v) { return v; });

    // the file stores points voxel by voxel: restore ascending id order
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return ids[a] < ids[b]; });
    cloud.P = permuted(P, order);
    cloud.id = permuted(ids, order);

    for (size_t pos = 0; pos < names.size(); ++pos) {
        const std::string& name = names[pos];
        if (name == "P" || name == "id") continue;
        const std::string type = descriptor.valueType(pos);
        if (type == openvdb::typeNameAsString<float>()) {
            std::vector<float> values;
            values.reserve(n);
            gather<float>(tree, pos, values, [](float v) { return v; });
            cloud.floats.emplace_back(name, permuted(values, order));
        } else if (type == openvdb::typeNameAsString<openvdb::Vec3f>()) {
            std::vector<Vec3f> values;
            values.reserve(n);
            gather<openvdb::Vec3f>(tree, pos, values,
                                   [](const openvdb::Vec3f& v) { return from_vdb(v); });
            cloud.vec3s.emplace_back(name, permuted(values, order));
        } else if (type == openvdb::typeNameAsString<openvdb::math::Mat3s>()) {
            std::vector<Mat3f> values;
            values.reserve(n);
            gather<openvdb::math::Mat3s>(tree, pos, values,
                                         [](const openvdb::math::Mat3s& m) { return from_vdb(m); });
            cloud.mat3s.emplace_back(name, permuted(values, order));
        }
        // other types (groups, strings, doubles from other tools) are not part of our format
    }
    return cloud;
}

PointCloud frame_to_points(const ParticleFrame& frame) {
    PointCloud cloud;
    cloud.P = frame.P;
    cloud.id.resize(frame.size());
    std::iota(cloud.id.begin(), cloud.id.end(), 0);
#define MC_ADD_CACHED(T, member, key, vdb, physics, policy, doc) \
    if (!frame.member.empty()) attributes_of<T>(cloud).emplace_back(vdb, frame.member);
    MC_CACHED_ATTRIBUTES(MC_ADD_CACHED)
#undef MC_ADD_CACHED
    cloud.meta_string["mudcrack:stage"] = "sim";
    cloud.meta_int["mudcrack:frame"] = frame.frame;
    cloud.meta_int["mudcrack:substeps"] = frame.substeps;
    cloud.meta_double["mudcrack:time"] = frame.time;
    return cloud;
}

ParticleFrame points_to_frame(const PointCloud& cloud, const std::string& source) {
    const size_t n = cloud.P.size();
    if (cloud.id.size() != n) {
        throw InputError(source + ": " + std::to_string(cloud.id.size()) + " ids for " +
                         std::to_string(n) + " points");
    }
    // ids must be a permutation of 0..n-1: slot[id] = the point's index in the cloud
    std::vector<size_t> slot(n, n);
    for (size_t i = 0; i < n; ++i) {
        const int32_t id = cloud.id[i];
        if (id < 0 || size_t(id) >= n || slot[size_t(id)] != n) {
            throw InputError(source + ": point " + std::to_string(i) + " has id " +
                             std::to_string(id) + ": expected each of the ids 0.." +
                             std::to_string(int64_t(n) - 1) + " exactly once");
        }
        slot[size_t(id)] = i;
    }
    auto by_id = [&](const auto& values, const std::string& name) {
        using Vector = std::decay_t<decltype(values)>;
        if (values.size() != n) {
            throw InputError(source + ": attribute '" + name + "' has " +
                             std::to_string(values.size()) + " values for " + std::to_string(n) +
                             " points");
        }
        Vector out(n);
        for (size_t id = 0; id < n; ++id) out[id] = values[slot[id]];
        return out;
    };

    ParticleFrame frame;
    frame.P = by_id(cloud.P, "P");
#define MC_READ_CACHED(T, member, key, vdb, physics, policy, doc) \
    if (const auto* values = find_attribute<T>(cloud, vdb)) frame.member = by_id(*values, vdb);
    MC_CACHED_ATTRIBUTES(MC_READ_CACHED)
#undef MC_READ_CACHED
    if (auto it = cloud.meta_int.find("mudcrack:frame"); it != cloud.meta_int.end())
        frame.frame = int(it->second);
    if (auto it = cloud.meta_int.find("mudcrack:substeps"); it != cloud.meta_int.end())
        frame.substeps = int(it->second);
    if (auto it = cloud.meta_double.find("mudcrack:time"); it != cloud.meta_double.end())
        frame.time = it->second;
    return frame;
}

fs::path frame_path(const fs::path& dir, const std::string& stem, int frame,
                    const std::string& ext) {
    char number[16];
    std::snprintf(number, sizeof number, "%04d", frame);
    const std::string suffix = ext.empty() || ext[0] == '.' ? ext : "." + ext;
    return dir / (stem + "." + number + suffix);
}

}  // namespace mudcrack
