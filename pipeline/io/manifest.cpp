#include "pipeline/io/manifest.h"

#include <unistd.h>

#include <ctime>
#include <fstream>
#include <system_error>
#include <thread>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/checksum.h"
#include "pipeline/io/mesh_io.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {

namespace {

constexpr const char* kManifestName = "manifest.json";

/// The stage binary that writes a folder, named after it: out/demo/init -> mc-init.
std::string producer_of(const fs::path& dir) {
    std::string stage = dir.filename().string();
    if (stage.empty()) stage = dir.parent_path().filename().string();
    return "mc-" + stage;
}

std::string utc_now_iso8601() {
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
    return text;
}

std::string host_name() {
    char name[256] = {0};
    if (gethostname(name, sizeof name - 1) != 0) return "unknown";
    return name;
}

}  // namespace

nlohmann::json make_manifest(const std::string& stage, const std::string& shot_path,
                             const std::string& slice_hash) {
    nlohmann::json m;
    m["stage"] = stage;
    m["version"] = MUDCRACK_VERSION;
    m["shot"] = shot_path;
    m["shot_slice_hash"] = slice_hash;
    m["created_utc"] = utc_now_iso8601();
    m["host"] = host_name();
    m["threads"] = thread_count();                                 // workers this run uses
    m["host_threads"] = int(std::thread::hardware_concurrency());  // what the machine offers
    return m;
}

std::string manifest_slice_hash(const nlohmann::json& manifest) {
    const auto it = manifest.find("shot_slice_hash");
    return it != manifest.end() && it->is_string() ? it->get<std::string>() : std::string();
}

void write_manifest(const fs::path& dir, const nlohmann::json& manifest) {
    write_text_atomically(dir / kManifestName, manifest.dump(2) + "\n");
}

nlohmann::json read_manifest(const fs::path& dir) {
    const fs::path path = dir / kManifestName;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw InputError(path.string() + ": missing: run " + producer_of(dir) + " first");
    }
    std::ifstream is(path);
    nlohmann::json manifest = nlohmann::json::parse(is, nullptr, /*allow_exceptions=*/false,
                                                    /*ignore_comments=*/true);
    if (manifest.is_discarded() || !manifest.is_object()) {
        throw InputError(path.string() +
                         ": malformed manifest: expected a JSON object (re-run the "
                         "stage that wrote it)");
    }
    return manifest;
}

nlohmann::json read_current_manifest(const fs::path& dir, const std::string& expected_slice_hash) {
    nlohmann::json manifest = read_manifest(dir);
    const std::string file = (dir / kManifestName).string();
    const auto hash = manifest.find("shot_slice_hash");
    if (hash == manifest.end())
        throw InputError(
            file +
            ": /shot_slice_hash: missing, so it cannot be checked against this shot: re-run " +
            producer_of(dir));
    if (!hash->is_string() || hash->get<std::string>().empty())
        throw InputError(file + ": /shot_slice_hash = " + hash->dump() +
                         ": not a slice hash: re-run " + producer_of(dir));
    const std::string found = hash->get<std::string>();
    if (found != expected_slice_hash)
        throw InputError(file + ": /shot_slice_hash = \"" + found +
                         "\": stale for this shot (expected \"" + expected_slice_hash +
                         "\"): re-run " + producer_of(dir));
    return manifest;
}

ManifestFrames manifest_frames(const json& manifest, const fs::path& manifest_file) {
    try {
        return {manifest.at("frames").at("first").get<int>(),
                manifest.at("frames").at("last").get<int>()};
    } catch (const json::exception&) {
        throw InputError(manifest_file.string() +
                         ": /frames/first and /frames/last: missing or not integers");
    }
}

json file_record(const fs::path& file) {
    return {{"file", file.filename().string()}, {"crc32", file_crc32(file)}};
}

RecordedChecksums::RecordedChecksums(const json& manifest, const fs::path& manifest_file) {
    add(manifest, manifest_file);
}

void RecordedChecksums::add(const json& manifest, const fs::path& manifest_file) {
    m_verified = std::make_shared<Verified>();  // new records: nothing is verified against them yet
    add_records(manifest, manifest_file);
}

void RecordedChecksums::add_records(const json& manifest, const fs::path& manifest_file) {
    if (manifest.is_array()) {
        for (const json& item : manifest) add_records(item, manifest_file);
        return;
    }
    if (!manifest.is_object()) return;
    const auto file = manifest.find("file"), crc = manifest.find("crc32");
    if (file != manifest.end() && crc != manifest.end() && file->is_string() && crc->is_string())
        m_records[file->get<std::string>()] = {crc->get<std::string>(), manifest_file};
    for (const auto& [key, value] : manifest.items())
        if (value.is_structured()) add_records(value, manifest_file);
}

void RecordedChecksums::verify(const fs::path& file) const {
    {
        const std::lock_guard<std::mutex> lock(m_verified->mutex);
        if (m_verified->files.count(file)) return;
    }
    const fs::path dir = file.parent_path();
    const std::string rerun = ": re-run " + producer_of(dir);
    const auto it = m_records.find(file.filename().string());
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) throw InputError(file.string() + ": missing" + rerun);
    if (it == m_records.end())
        throw InputError(file.string() + ": no checksum recorded for it, so it cannot be verified" +
                         rerun);
    const std::string found = file_crc32(file);
    if (found != it->second.crc32)
        throw InputError(file.string() + ": damaged: its CRC-32 is " + found + ", but " +
                         it->second.manifest_file.string() + " records " + it->second.crc32 +
                         rerun);
    {
        const std::lock_guard<std::mutex> lock(m_verified->mutex);
        m_verified->files.insert(file);
    }
    // an obj mesh's readers load its material file too: checked with it where it is recorded
    const fs::path material = mesh_material_file(file);
    if (!material.empty() && has(material.filename().string())) verify(material);
}

void RecordedChecksums::verify_all(const fs::path& dir) const {
    for (const auto& [name, record] : m_records) verify(dir / name);
}

}  // namespace mudcrack
