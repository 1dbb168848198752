#pragma once
/// Review movies through Debian's ffmpeg: rendered frames are streamed as raw RGBA into an
/// `ffmpeg` child process (H.264 / libx264, yuv420p, odd sizes padded to even), so no
/// intermediate files are needed and frames need not stay in memory.
#include <sys/types.h>
#include <filesystem>
#include <string>

#include "render/renderer.h"

namespace mudcrack {

/// The full path of `program` found on PATH, or empty if it is not there.
std::string find_on_path(const std::string& program);

class MovieEncoder {
public:
    /// Starts `ffmpeg` writing `path` (through a temporary name). Throws RuntimeError if ffmpeg
    /// is not on PATH or cannot be started, InputError for a non-positive size or fps.
    MovieEncoder(std::filesystem::path path, int width, int height, double fps);
    /// Without finish(): stops ffmpeg and removes the temporary file (no half-written movie).
    ~MovieEncoder();
    MovieEncoder(const MovieEncoder&) = delete;
    MovieEncoder& operator=(const MovieEncoder&) = delete;

    /// Appends a frame of the encoder's size. Throws InputError for another size,
    /// RuntimeError if ffmpeg stopped reading.
    void add_frame(const RenderedImage& image);
    /// Ends the stream, waits for ffmpeg and renames the movie into place. Throws RuntimeError
    /// if ffmpeg failed (the temporary file is removed).
    void finish();

    int frame_count() const { return m_frames; }

private:
    void close_and_wait(int* status);
    /// ": <ffmpeg's last error line>", or "" when it wrote none (waits for ffmpeg to exit).
    std::string ffmpeg_reason();

    std::filesystem::path m_path, m_tmp;
    int m_width, m_height;
    int m_fd = -1;
    int m_log_fd = -1;  // ffmpeg's stderr, in memory: its message joins ours in one line
    pid_t m_pid = -1;
    int m_frames = 0;
    bool m_finished = false;
};

}  // namespace mudcrack
