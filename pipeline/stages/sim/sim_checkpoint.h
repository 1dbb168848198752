#pragma once
/// mc-sim's full-precision checkpoints: every SimState (or SimStateFloat) array bit for bit (in
/// its sorted slot order; a float state's arrays as the doubles that hold them exactly, marked
/// "precision" = "float"), the time and step count, the run's counters, and the shot's sim slice
/// hash, in DIR/sim/checkpoint.####.bin (#### = the frame whose end the state is at). `--resume`
/// restarts from one and must then produce caches bitwise identical to an uninterrupted run.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "pipeline/stages/sim/sim_frame_stepper.h"
#include "sim/mpm/simulation.h"

namespace mudcrack {

/// A simulation state at the end of a frame, with what is needed to trust and continue it. S: the
/// state's precision (SimStateOf).
template <class S>
struct SimCheckpointOf {
    int frame = 0;           // the state is at the end of this frame (time = frame / fps)
    std::string slice_hash;  // Shot::slice_hash(Stage::Sim) of the run that wrote it
    int threads = 0;         // worker threads of that run (bitwise determinism is per count)
    SimStateOf<S> state;     // workspace is not saved (step() rebuilds it)
    SimTotals totals;        // counters from t = 0 to the end of `frame`
    // the CRC-32 (file_crc32) of every frame cache the runs leading here wrote, by frame: what a
    // resume checks the frames it keeps against, since the manifest that records them is written
    // only when a run completes
    std::map<int, std::string> cache_crc32;
};

using SimCheckpoint = SimCheckpointOf<double>;

/// "dir/checkpoint.0042.bin".
std::filesystem::path checkpoint_path(const std::filesystem::path& dir, int frame);

/// Frames of the checkpoint files in `dir` (by name only, not validated), ascending.
std::vector<int> list_checkpoint_frames(const std::filesystem::path& dir);

/// Writes a checkpoint atomically (tmp + rename) with a checksum over its contents.
template <class S>
void write_sim_checkpoint(const std::filesystem::path& path, const SimCheckpointOf<S>& checkpoint);

/// Reads a checkpoint written by write_sim_checkpoint. Throws InputError naming the file when it
/// is missing, truncated, fails its checksum, is of another format, or its arrays are
/// inconsistent (sizes differ from the particle count), or holds a state of the other precision.
template <class S = double>
SimCheckpointOf<S> read_sim_checkpoint(const std::filesystem::path& path);

}  // namespace mudcrack
