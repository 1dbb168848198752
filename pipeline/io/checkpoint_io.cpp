#include "pipeline/io/checkpoint_io.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>
#include <type_traits>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/checksum.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

namespace {

constexpr char kMagic[8] = {'M', 'C', 'C', 'K', 'P', 'T', '1', '\0'};

enum class EntryKind : uint8_t {
    F64Array = 1,
    I32Array = 2,
    I64Array = 3,
    String = 4,
    F64 = 5,
    I64 = 6
};

constexpr bool kHostIsLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

// reverses the bytes of each `width`-byte element (big-endian hosts only)
void swap_elements(char* data, size_t count, size_t width) {
    for (size_t i = 0; i < count; ++i) std::reverse(data + i * width, data + (i + 1) * width);
}

/// Streams little-endian values to a file while hashing every byte written.
class ChecksummedWriter {
public:
    explicit ChecksummedWriter(const fs::path& path) : m_os(path, std::ios::binary), m_path(path) {
        if (!m_os)
            throw RuntimeError(path.string() +
                               ": cannot open for writing: " + write_error_reason());
    }
    void raw(const void* data, size_t size) {
        m_hash = fnv1a64(data, size, m_hash);
        m_os.write(static_cast<const char*>(data), std::streamsize(size));
    }
    template <class T>
    void value(T v) {
        array(&v, 1);
    }
    template <class T>
    void array(const T* values, size_t count) {
        static_assert(std::is_arithmetic_v<T>);
        if constexpr (kHostIsLittleEndian || sizeof(T) == 1) {
            raw(values, count * sizeof(T));
        } else {
            constexpr size_t kChunk = 4096;
            std::array<T, kChunk> buffer;
            for (size_t i = 0; i < count; i += kChunk) {
                const size_t n = std::min(kChunk, count - i);
                std::memcpy(buffer.data(), values + i, n * sizeof(T));
                swap_elements(reinterpret_cast<char*>(buffer.data()), n, sizeof(T));
                raw(buffer.data(), n * sizeof(T));
            }
        }
    }
    void name(const std::string& s) {
        value(uint32_t(s.size()));
        raw(s.data(), s.size());
    }
    /// Appends the checksum of everything so far and closes the file.
    void finish() {
        const uint64_t hash = m_hash;
        value(hash);
        m_os.close();
        if (!m_os) throw RuntimeError(m_path.string() + ": cannot write: " + write_error_reason());
    }

private:
    std::ofstream m_os;
    fs::path m_path;
    uint64_t m_hash = kFnv1a64Offset;
};

/// Reads little-endian values while hashing every byte read; any short read is a truncated file.
class ChecksummedReader {
public:
    explicit ChecksummedReader(const fs::path& path) : m_is(path, std::ios::binary), m_path(path) {
        std::error_code ec;
        m_size = fs::file_size(path, ec);
        if (!m_is || ec)
            throw InputError(path.string() + ": checkpoint file not found or not readable");
    }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path.string() + ": " + what);
    }
    uint64_t remaining() const { return m_size - m_pos; }
    void raw(void* data, size_t size) {
        if (size > remaining() || !m_is.read(static_cast<char*>(data), std::streamsize(size))) {
            fail("truncated checkpoint: needs " + std::to_string(size) + " more bytes at byte " +
                 std::to_string(m_pos) + " of " + std::to_string(m_size));
        }
        m_pos += size;
        m_hash = fnv1a64(data, size, m_hash);
    }
    template <class T>
    T value() {
        T v;
        array(&v, 1);
        return v;
    }
    template <class T>
    void array(T* values, size_t count) {
        raw(values, count * sizeof(T));
        if constexpr (!kHostIsLittleEndian && sizeof(T) > 1) {
            swap_elements(reinterpret_cast<char*>(values), count, sizeof(T));
        }
    }
    /// An element count for `width`-byte elements, refused before allocating when the file is too
    /// short.
    size_t count(const std::string& entry, size_t width) {
        const uint64_t n = value<uint64_t>();
        // leave room for the trailing checksum
        if (remaining() < sizeof(uint64_t) || n > (remaining() - sizeof(uint64_t)) / width) {
            fail("entry '" + entry + "' claims " + std::to_string(n) + " elements but only " +
                 std::to_string(remaining()) + " bytes remain (truncated or damaged checkpoint)");
        }
        return size_t(n);
    }
    std::string name() {
        const uint32_t n = value<uint32_t>();
        if (n > remaining())
            fail("entry name length " + std::to_string(n) +
                 " exceeds the file (damaged checkpoint)");
        std::string s(n, '\0');
        raw(s.data(), n);
        return s;
    }
    uint64_t hash() const { return m_hash; }

private:
    std::ifstream m_is;
    fs::path m_path;
    uint64_t m_size = 0, m_pos = 0;
    uint64_t m_hash = kFnv1a64Offset;
};

template <class T>
void write_arrays(ChecksummedWriter& w, EntryKind kind,
                  const std::map<std::string, std::vector<T>>& arrays) {
    for (const auto& [name, values] : arrays) {
        w.value(uint8_t(kind));
        w.name(name);
        w.value(uint64_t(values.size()));
        w.array(values.data(), values.size());
    }
}

template <class T>
void read_array(ChecksummedReader& r, const std::string& name,
                std::map<std::string, std::vector<T>>& into) {
    std::vector<T> values(r.count(name, sizeof(T)));
    r.array(values.data(), values.size());
    if (!into.emplace(name, std::move(values)).second) r.fail("duplicate array '" + name + "'");
}

template <class Map>
const typename Map::mapped_type& require(const Map& map, const std::string& name,
                                         const std::string& source, const char* kind) {
    const auto it = map.find(name);
    if (it == map.end())
        throw InputError(source + ": checkpoint has no " + kind + " '" + name + "'");
    return it->second;
}

template <class T>
const std::vector<T>& require_sized(const std::map<std::string, std::vector<T>>& map,
                                    const std::string& name, size_t expected_size,
                                    const std::string& source, const char* kind) {
    const auto& values = require(map, name, source, kind);
    if (expected_size != SIZE_MAX && values.size() != expected_size) {
        throw InputError(source + ": checkpoint " + kind + " '" + name + "' has " +
                         std::to_string(values.size()) + " elements, expected " +
                         std::to_string(expected_size));
    }
    return values;
}

}  // namespace

const std::vector<double>& Checkpoint::require_f64(const std::string& name,
                                                   size_t expected_size) const {
    return require_sized(f64, name, expected_size, source, "float64 array");
}
const std::vector<int32_t>& Checkpoint::require_i32(const std::string& name,
                                                    size_t expected_size) const {
    return require_sized(i32, name, expected_size, source, "int32 array");
}
const std::vector<int64_t>& Checkpoint::require_i64(const std::string& name,
                                                    size_t expected_size) const {
    return require_sized(i64, name, expected_size, source, "int64 array");
}
double Checkpoint::require_double(const std::string& name) const {
    return require(meta_double, name, source, "float64 scalar");
}
int64_t Checkpoint::require_int(const std::string& name) const {
    return require(meta_int, name, source, "int64 scalar");
}
const std::string& Checkpoint::require_string(const std::string& name) const {
    return require(meta_string, name, source, "string");
}

void write_checkpoint(const fs::path& path, const Checkpoint& c) {
    const size_t entries = c.f64.size() + c.i32.size() + c.i64.size() + c.meta_string.size() +
                           c.meta_double.size() + c.meta_int.size();
    write_atomically(path, [&](const fs::path& tmp) {
        errno = 0;  // so a failure reports its own reason
        ChecksummedWriter w(tmp);
        w.raw(kMagic, sizeof kMagic);
        w.value(kCheckpointFormatVersion);
        w.value(uint32_t(entries));
        write_arrays(w, EntryKind::F64Array, c.f64);
        write_arrays(w, EntryKind::I32Array, c.i32);
        write_arrays(w, EntryKind::I64Array, c.i64);
        for (const auto& [name, text] : c.meta_string) {
            w.value(uint8_t(EntryKind::String));
            w.name(name);
            w.value(uint64_t(text.size()));
            w.raw(text.data(), text.size());
        }
        for (const auto& [name, v] : c.meta_double) {
            w.value(uint8_t(EntryKind::F64));
            w.name(name);
            w.value(uint64_t(1));
            w.value(v);
        }
        for (const auto& [name, v] : c.meta_int) {
            w.value(uint8_t(EntryKind::I64));
            w.name(name);
            w.value(uint64_t(1));
            w.value(v);
        }
        w.finish();
    });
}

Checkpoint read_checkpoint(const fs::path& path) {
    ChecksummedReader r(path);
    char magic[sizeof kMagic];
    if (r.remaining() < sizeof kMagic)
        r.fail("not a mudcrack checkpoint (too short for the MCCKPT1 header)");
    r.raw(magic, sizeof magic);
    if (std::memcmp(magic, kMagic, sizeof kMagic) != 0)
        r.fail("not a mudcrack checkpoint (no MCCKPT1 magic)");
    const auto version = r.value<uint32_t>();
    if (version != kCheckpointFormatVersion) {
        r.fail("checkpoint format version " + std::to_string(version) +
               ": this build reads version " + std::to_string(kCheckpointFormatVersion) + " only");
    }
    Checkpoint c;
    c.source = path.string();
    const auto entries = r.value<uint32_t>();
    for (uint32_t e = 0; e < entries; ++e) {
        const auto kind = r.value<uint8_t>();
        const std::string name = r.name();
        switch (EntryKind(kind)) {
            case EntryKind::F64Array: read_array(r, name, c.f64); break;
            case EntryKind::I32Array: read_array(r, name, c.i32); break;
            case EntryKind::I64Array: read_array(r, name, c.i64); break;
            case EntryKind::String: {
                std::string text(r.count(name, 1), '\0');
                r.raw(text.data(), text.size());
                if (!c.meta_string.emplace(name, std::move(text)).second)
                    r.fail("duplicate string '" + name + "'");
                break;
            }
            case EntryKind::F64:
            case EntryKind::I64: {
                if (r.count(name, 8) != 1)
                    r.fail("scalar '" + name + "' must have exactly one element");
                const bool inserted = EntryKind(kind) == EntryKind::F64
                                          ? c.meta_double.emplace(name, r.value<double>()).second
                                          : c.meta_int.emplace(name, r.value<int64_t>()).second;
                if (!inserted) r.fail("duplicate scalar '" + name + "'");
                break;
            }
            default:
                r.fail("entry " + std::to_string(e) + " ('" + name + "') has unknown kind " +
                       std::to_string(int(kind)) + " (damaged checkpoint?)");
        }
    }
    const uint64_t computed = r.hash();
    const auto stored = r.value<uint64_t>();
    if (stored != computed) r.fail("checksum mismatch: the checkpoint is damaged");
    if (r.remaining() != 0) {
        r.fail(std::to_string(r.remaining()) +
               " unexpected bytes after the checksum (damaged checkpoint)");
    }
    return c;
}

}  // namespace mudcrack
