#pragma once
/// mc-sim's progress report on stderr: frame, substeps, simulated time,
/// particle-steps/s and ETA. On a terminal one line is rewritten in place with '\r' (at most a
/// few times a second); otherwise (a log file, make -j) one plain line per finished frame.
#include <cstdint>
#include <cstdio>
#include <string>

#include "sim/core/stats.h"

namespace mudcrack {

class SimProgress {
public:
    /// @param particles particle count (for particle-steps/s)
    /// @param first_frame, last_frame the frames this run writes (1-based, inclusive)
    /// @param t_begin, t_end simulated time [s] at the start of the run and at the last frame's end
    /// @param enabled false for --quiet: nothing is printed
    /// @param stream where to print (stderr); is_terminal selects the '\r' style
    SimProgress(int64_t particles, int first_frame, int last_frame, double t_begin, double t_end,
                bool enabled, std::FILE* stream, bool is_terminal);

    /// After every substep: the frame being computed, its substeps so far, the simulated time,
    /// and the seconds spent in the step loop so far (the rate's denominator).
    void substep(int frame, int frame_substeps, double time, int64_t total_substeps,
                 double step_seconds);
    /// After a frame's cache is written.
    void frame_done(int frame, int frame_substeps, double time, int64_t total_substeps,
                    double step_seconds);
    /// Ends the '\r' line (if any) so later log lines start on a fresh line.
    void finish();

    /// "1h02m", "3m07s", "12s", or "?" for a negative/non-finite value.
    static std::string format_duration(double seconds);

private:
    std::string line(int frame, int frame_substeps, double time, int64_t total_substeps,
                     double step_seconds) const;

    int64_t m_particles;
    int m_first_frame, m_last_frame;
    double m_t_begin, m_t_end;
    bool m_enabled;
    std::FILE* m_stream;
    bool m_is_terminal;
    bool m_line_open = false;  // a '\r' line is on screen without its newline
    WallTimer m_wall;          // since the run started (for the ETA)
    double m_last_print = -1;  // wall seconds of the last '\r' update
};

/// True when `stream` is attached to a terminal.
bool is_terminal(std::FILE* stream);

}  // namespace mudcrack
