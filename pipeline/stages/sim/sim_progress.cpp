#include "pipeline/stages/sim/sim_progress.h"

#include <unistd.h>

#include <cmath>
#include <string>

namespace mudcrack {
namespace {
constexpr double kTerminalRefreshSeconds = 0.25;  // '\r' updates per second are cheap but noisy
}  // namespace

bool is_terminal(std::FILE* stream) { return isatty(fileno(stream)) != 0; }

SimProgress::SimProgress(int64_t particles, int first_frame, int last_frame, double t_begin,
                         double t_end, bool enabled, std::FILE* stream, bool is_terminal)
    : m_particles(particles),
      m_first_frame(first_frame),
      m_last_frame(last_frame),
      m_t_begin(t_begin),
      m_t_end(t_end),
      m_enabled(enabled),
      m_stream(stream),
      m_is_terminal(is_terminal) {}

std::string SimProgress::format_duration(double seconds) {
    if (!std::isfinite(seconds) || seconds < 0) return "?";
    const int64_t s = std::llround(seconds);
    char buf[32];
    if (s >= 3600)
        std::snprintf(buf, sizeof buf, "%lldh%02lldm", (long long)(s / 3600),
                      (long long)(s % 3600 / 60));
    else if (s >= 60)
        std::snprintf(buf, sizeof buf, "%lldm%02llds", (long long)(s / 60), (long long)(s % 60));
    else
        std::snprintf(buf, sizeof buf, "%llds", (long long)s);
    return buf;
}

std::string SimProgress::line(int frame, int frame_substeps, double time, int64_t total_substeps,
                              double step_seconds) const {
    // the rate counts step-loop time only; the ETA scales the whole wall time by the simulated
    // time still to go, so cache writing and checkpoints are included in it
    const double rate =
        step_seconds > 0 ? double(total_substeps) * double(m_particles) / step_seconds : 0;
    const double done = time - m_t_begin, todo = m_t_end - time;
    const double eta = done > 0 ? m_wall.seconds() * todo / done : -1;
    char buf[256];
    std::snprintf(
        buf, sizeof buf,
        "frame %d/%d (%d of %d) substeps %d (total %lld) t = %.4f s, %.2f M particle-steps/s, ETA %s",
        frame, m_last_frame, frame - m_first_frame + 1, m_last_frame - m_first_frame + 1,
        frame_substeps, (long long)total_substeps, time, rate * 1e-6, format_duration(eta).c_str());
    return buf;
}

void SimProgress::substep(int frame, int frame_substeps, double time, int64_t total_substeps,
                          double step_seconds) {
    if (!m_enabled || !m_is_terminal) return;
    const double now = m_wall.seconds();
    if (m_last_print >= 0 && now - m_last_print < kTerminalRefreshSeconds) return;
    m_last_print = now;
    // pad with spaces so a shorter line fully covers the previous one
    std::fprintf(m_stream, "\r%-110s",
                 line(frame, frame_substeps, time, total_substeps, step_seconds).c_str());
    std::fflush(m_stream);
    m_line_open = true;
}

void SimProgress::frame_done(int frame, int frame_substeps, double time, int64_t total_substeps,
                             double step_seconds) {
    if (!m_enabled) return;
    const std::string text = line(frame, frame_substeps, time, total_substeps, step_seconds);
    if (m_is_terminal) {
        std::fprintf(m_stream, "\r%-110s", text.c_str());
        m_line_open = true;
        m_last_print = m_wall.seconds();
    } else {
        std::fprintf(m_stream, "mc-sim: %s\n", text.c_str());
    }
    std::fflush(m_stream);
}

void SimProgress::finish() {
    if (m_line_open) std::fputc('\n', m_stream);
    m_line_open = false;
    std::fflush(m_stream);
}

}  // namespace mudcrack
