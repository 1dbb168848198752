#pragma once
/// The options every stage library takes: what the stage programs' shared flags (--shot, --out,
/// --frames, --threads, --seed, --log-level, --quiet, --keep-partial) parsed into. The stage
/// libraries sit below the mains (pipeline/cmd/), so this type lives here, not with the parser
/// (pipeline/cmd/stage_cli.h), and a stage library never sees CLI11.
#include <string>

namespace mudcrack {

struct FrameRange {
    int first = 0;  // 0 = from the shot
    int last = 0;   // 0 = from the shot
    bool is_set() const { return first > 0; }
};

struct StageOptions {
    std::string program;        // e.g. "mc-sim"
    std::string shot;           // --shot
    std::string out;            // --out: the shot's output root (stages write DIR/<stage>/)
    std::string frames;         // --frames A-B or N (as given)
    FrameRange frame_range;     // parsed --frames
    int threads = 0;            // --threads (0 = all cores)
    unsigned seed = 0;          // --seed (0 = the shot's)
    bool quiet = false;         // --quiet: errors and warnings only
    bool keep_partial = false;  // --keep-partial: keep .partial/ folders of a failed run
    std::string log_level = "info";
};

/// The frames a stage works on: --frames when given, else all of `available`. The one check of
/// --frames against the frames there are, so every stage refuses a range outside them alike.
/// Throws UsageError ("--frames A-B: outside the frames F-L of <where>") when --frames is not
/// within `available`.
/// @param available the frames the stage's input holds (the shot's, or a manifest's /frames)
/// @param where what `available` comes from, for the message (a file, with its keys)
FrameRange frames_to_process(const StageOptions& options, const FrameRange& available,
                             const std::string& where);

}  // namespace mudcrack
