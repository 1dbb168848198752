#pragma once
/// Each stage writes manifest.json last (style.md 2): stage, tool version, the hash of the shot
/// slice it read, its input manifests, frame range, wall time, measured rates, peak memory, and
/// what it ran and allocated.
#include <filesystem>
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

}  // namespace mudcrack
