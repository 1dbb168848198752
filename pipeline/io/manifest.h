#pragma once
/// Each stage writes manifest.json last (docs/architecture.md §3): stage, tool version, the hash of
/// the shot slice it read, its input manifests, frame range, wall time, measured rates, peak
/// memory, and what it ran and allocated.
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

/// Reads dir/manifest.json, the manifest of the stage a later stage reads from, and checks that it
/// is current: it exists, parses, records a "shot_slice_hash", and that hash is the one the shot's
/// slice of that stage hashes to now. Every stage reads its inputs through this one check, so a
/// missing, malformed, unhashed or stale input is refused with the same message wherever it is
/// read, naming the file, the key and the value (e.g. "out/demo/sim/manifest.json:
/// /shot_slice_hash = "9f..": stale for this shot (expected "3c.."): re-run mc-sim").
/// @param expected_slice_hash Shot::slice_hash of the stage that wrote dir
nlohmann::json read_current_manifest(const std::filesystem::path& dir, const std::string& expected_slice_hash);

}  // namespace mudcrack
