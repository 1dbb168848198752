#include "pipeline/io/debris_io.h"

#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "pipeline/io/atomic_output.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "debris PLY files are little-endian, written as in memory");

constexpr const char* kProperties =
    "property float x\nproperty float y\nproperty float z\n"
    "property float vx\nproperty float vy\nproperty float vz\n"
    "property float pscale\nproperty int id\nproperty int piece\n";
constexpr size_t kRecordBytes = 7 * sizeof(float) + 2 * sizeof(int32_t);

std::string header(size_t count) {
    return "ply\nformat binary_little_endian 1.0\ncomment mudcrack debris (docs/physics.md 5.7)\nelement vertex " +
           std::to_string(count) + "\n" + kProperties + "end_header\n";
}

}  // namespace

void write_debris_ply(const std::filesystem::path& path, const DebrisPoints& debris) {
    const size_t n = debris.size();
    std::string body(n * kRecordBytes, '\0');
    for (size_t i = 0; i < n; ++i) {
        const float f[7] = {debris.position[i].x(), debris.position[i].y(), debris.position[i].z(),
                            debris.velocity[i].x(), debris.velocity[i].y(), debris.velocity[i].z(),
                            debris.radius[i]};
        const int32_t k[2] = {debris.id[i], debris.piece[i]};
        std::memcpy(&body[i * kRecordBytes], f, sizeof f);
        std::memcpy(&body[i * kRecordBytes + sizeof f], k, sizeof k);
    }
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        errno = 0;
        std::ofstream out(tmp, std::ios::binary);
        out << header(n);
        out.write(body.data(), static_cast<std::streamsize>(body.size()));
        out.close();
        if (!out) throw RuntimeError(path.string() + ": cannot write: " + write_error_reason());
    });
}

DebrisPoints read_debris_ply(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string() + ": cannot open");
    std::string line, text;
    size_t count = 0;
    while (std::getline(in, line) && line != "end_header") {
        text += line + "\n";
        if (line.rfind("element vertex ", 0) == 0) {
            try {
                count = std::stoull(line.substr(15));
            } catch (const std::exception&) {
                throw InputError(path.string() + ": '" + line + "': not a vertex count");
            }
        }
    }
    if (line != "end_header" || text + "end_header\n" != header(count))
        throw InputError(
            path.string() +
            ": not a mudcrack debris PLY (its header differs from docs/physics.md 5.7's)");
    const auto body_start = in.tellg();
    in.seekg(0, std::ios::end);
    const auto available = static_cast<size_t>(in.tellg() - body_start);
    in.seekg(body_start);
    if (available != count * kRecordBytes)
        throw InputError(path.string() + ": truncated or too long: " + std::to_string(count) +
                         " debris points take " + std::to_string(count * kRecordBytes) +
                         " bytes; the file holds " + std::to_string(available));
    std::string body(count * kRecordBytes, '\0');
    in.read(body.data(), static_cast<std::streamsize>(body.size()));
    if (in.gcount() != static_cast<std::streamsize>(body.size()))
        throw InputError(path.string() + ": cannot read");
    DebrisPoints d;
    for (size_t i = 0; i < count; ++i) {
        float f[7];
        int32_t k[2];
        std::memcpy(f, &body[i * kRecordBytes], sizeof f);
        std::memcpy(k, &body[i * kRecordBytes + sizeof f], sizeof k);
        d.position.emplace_back(f[0], f[1], f[2]);
        d.velocity.emplace_back(f[3], f[4], f[5]);
        d.radius.push_back(f[6]);
        d.id.push_back(k[0]);
        d.piece.push_back(k[1]);
    }
    return d;
}

}  // namespace mudcrack
