#include "pipeline/io/manifest.h"

#include <unistd.h>

#include <ctime>
#include <fstream>
#include <system_error>
#include <thread>

#include "pipeline/io/atomic_output.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"

namespace fs = std::filesystem;

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
    m["threads"] = thread_count();                             // workers this run uses
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
        throw InputError(path.string() + ": malformed manifest: expected a JSON object (re-run the "
                                         "stage that wrote it)");
    }
    return manifest;
}

nlohmann::json read_current_manifest(const fs::path& dir, const std::string& expected_slice_hash) {
    nlohmann::json manifest = read_manifest(dir);
    const std::string file = (dir / kManifestName).string();
    const auto hash = manifest.find("shot_slice_hash");
    if (hash == manifest.end())
        throw InputError(file + ": /shot_slice_hash: missing, so it cannot be checked against this shot: re-run " +
                         producer_of(dir));
    if (!hash->is_string() || hash->get<std::string>().empty())
        throw InputError(file + ": /shot_slice_hash = " + hash->dump() + ": not a slice hash: re-run " +
                         producer_of(dir));
    const std::string found = hash->get<std::string>();
    if (found != expected_slice_hash)
        throw InputError(file + ": /shot_slice_hash = \"" + found + "\": stale for this shot (expected \"" +
                         expected_slice_hash + "\"): re-run " + producer_of(dir));
    return manifest;
}

}  // namespace mudcrack
