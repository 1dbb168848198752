#pragma once
/// What mc-shot does besides parsing (pipeline/shot does that): the one-line summary of a
/// shot, its stages for make, a stage's slice written only on change, and the table `make shot`
/// ends with.
#include <string>

#include "pipeline/shot/shot.h"

namespace mudcrack {

/// One line saying which stages and features the shot turns on.
std::string shot_summary(const Shot& shot);

/// The stages a shot turns on, in run order, e.g. "init sim surface render" (for make).
std::string stage_list(const Shot& shot);

/// Prints the canonical slice of `file` that stage `stage_name` reads, or writes it to `out`
/// only when its content changed (make compares mtimes). Returns the exit code (0).
int run_slice(const std::string& file, const std::string& stage_name, const std::string& out);

/// Prints per stage output folder under `out` the frames, wall time, throughput, peak memory and
/// outputs, as the stage's manifest recorded them: a table, or with `as_json` one JSON object
/// {"out", "stages": [{"stage", "dir", "shot", "frames": {"first", "last"} | null,
/// "resumed_from_frame", "wall_seconds", "peak_memory_bytes", "throughput": {"value", "unit"},
/// "files", "bytes"}]} (a value the manifest lacks is null). A sim resumed from a checkpoint
/// (frames "1-96 from 90" in the table) timed only the frames after it. Returns the exit code (0).
/// @throws InputError when `out` holds no stage's manifest
int run_summary(const std::string& out, bool as_json);

/// Verifies every file a stage manifest records (its "file" + "crc32" records, each file in the
/// manifest's folder) and prints "ok: N files verified against MANIFEST". The manifest may have
/// any name (the farm's merge checks its manifest before moving it into place). Returns 0.
/// @throws InputError naming the first missing or damaged file, or an unreadable manifest
int run_verify(const std::string& manifest_file);

}  // namespace mudcrack
