#pragma once
/// Each stage writes manifest.json last (docs/architecture.md §3): stage, tool version, the hash of
/// the shot slice it read, its input manifests, frame range, wall time, measured rates, peak
/// memory, and what it ran and allocated.
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

namespace mudcrack {

/// A manifest with the common fields filled in: stage, version, shot path, shot slice hash,
/// the current time (UTC, ISO 8601), and the host's thread count.
nlohmann::json make_manifest(const std::string& stage, const std::string& shot_path,
                             const std::string& slice_hash);

/// The hash of the shot slice a manifest was made from (make_manifest's "shot_slice_hash"),
/// or "" when it records none.
std::string manifest_slice_hash(const nlohmann::json& manifest);

/// Writes dir/manifest.json atomically, pretty-printed.
void write_manifest(const std::filesystem::path& dir, const nlohmann::json& manifest);

/// Reads dir/manifest.json. Throws InputError naming the file if it is missing or malformed
/// (e.g. "out/demo/init/manifest.json: missing: run mc-init first").
nlohmann::json read_manifest(const std::filesystem::path& dir);

/// Reads dir/manifest.json, the manifest of the stage a later stage reads from, and checks that it
/// is current: it exists, parses, records a "shot_slice_hash", and that hash is the one the shot's
/// slice of that stage hashes to now. Every stage reads its inputs through this one check, so a
/// missing, malformed, unhashed or stale input is refused with the same message wherever it is
/// read, naming the file, the key and the value (e.g. "out/demo/sim/manifest.json:
/// /shot_slice_hash = "9f..": stale for this shot (expected "3c.."): re-run mc-sim").
/// @param expected_slice_hash Shot::slice_hash of the stage that wrote dir
nlohmann::json read_current_manifest(const std::filesystem::path& dir,
                                     const std::string& expected_slice_hash);

/// The frames a stage's manifest covers, /frames/first to /frames/last (inclusive).
struct ManifestFrames {
    int first = 0;
    int last = -1;
};

/// Reads /frames/first and /frames/last. Throws InputError naming the file when either is missing
/// or not an integer.
/// @param manifest_file the manifest's path, for the message
ManifestFrames manifest_frames(const nlohmann::json& manifest,
                               const std::filesystem::path& manifest_file);

/// A manifest's record of a file it names, the one form every stage writes:
/// {"file": "<name in the manifest's folder>", "crc32": "<file_crc32 of its bytes>"}. Readers find
/// the records wherever the stage put them (/caches, /per_frame/*/boundary, /images, ...).
nlohmann::json file_record(const std::filesystem::path& file);

/// The file records of one or more manifests, by file name, so a reader checks every file it reads
/// against the checksum its writer recorded (docs/architecture.md §3).
class RecordedChecksums {
public:
    RecordedChecksums() = default;
    /// The records of `manifest`, read from `manifest_file` (see add).
    RecordedChecksums(const nlohmann::json& manifest, const std::filesystem::path& manifest_file);
    /// Adds every record found in `manifest` (any object holding a "file" and a "crc32" string),
    /// read from `manifest_file`; a later record of the same name wins.
    void add(const nlohmann::json& manifest, const std::filesystem::path& manifest_file);
    bool has(const std::string& file_name) const { return m_records.count(file_name) > 0; }
    size_t size() const { return m_records.size(); }
    /// Stops the reader unless `file` is the file its record vouches for. Throws InputError
    /// naming the file: "damaged" when its CRC-32 differs from the record, or no record / missing,
    /// each with the stage to re-run. A file verified once is not read again by this object (a
    /// stage that reads a file twice pays for one check). An obj mesh's material file
    /// (<stem>.mtl), which its readers load with it, is verified with it when it is recorded.
    /// Thread-safe.
    void verify(const std::filesystem::path& file) const;
    /// Verifies every recorded file, each found in `dir` (mc-shot verify, for the farm's scripts).
    void verify_all(const std::filesystem::path& dir) const;

private:
    void add_records(const nlohmann::json& manifest, const std::filesystem::path& manifest_file);

    struct Record {
        std::string crc32;
        std::filesystem::path manifest_file;
    };
    std::map<std::string, Record> m_records;
    // the files verified so far (shared by copies: they hold the same records)
    struct Verified {
        std::mutex mutex;
        std::set<std::filesystem::path> files;
    };
    std::shared_ptr<Verified> m_verified = std::make_shared<Verified>();
};

}  // namespace mudcrack
