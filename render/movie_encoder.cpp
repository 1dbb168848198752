#include "render/movie_encoder.h"

#include <pthread.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include "sim/core/error.h"

extern char** environ;

namespace fs = std::filesystem;

namespace mudcrack {

std::string find_on_path(const std::string& program) {
    const char* path = std::getenv("PATH");
    if (!path) return {};
    std::string dirs = path;
    size_t start = 0;
    while (start <= dirs.size()) {
        const size_t end = std::min(dirs.find(':', start), dirs.size());
        const std::string dir = dirs.substr(start, end - start);
        if (!dir.empty()) {
            const std::string candidate = dir + "/" + program;
            if (access(candidate.c_str(), X_OK) == 0) return candidate;
        }
        start = end + 1;
    }
    return {};
}

namespace {

// the last non-empty line ffmpeg wrote to `fd` (an in-memory file), trimmed; "" when none
std::string last_line_of(int fd) {
    if (fd < 0 || ::lseek(fd, 0, SEEK_SET) != 0) return {};
    std::string text;
    char buf[4096];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) text.append(buf, size_t(n));
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
        text.pop_back();
    const size_t start = text.find_last_of("\r\n");
    return start == std::string::npos ? text : text.substr(start + 1);
}

/// write() that reports a closed pipe as an error code instead of a fatal SIGPIPE: the signal
/// is blocked on this thread during the write and a pending one is consumed.
bool write_all(int fd, const uint8_t* data, size_t size) {
    sigset_t pipe_set, old_set;
    sigemptyset(&pipe_set);
    sigaddset(&pipe_set, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_set, &old_set);
    bool ok = true;
    while (size > 0) {
        const ssize_t n = ::write(fd, data, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            ok = false;
            break;
        }
        data += n;
        size -= size_t(n);
    }
    if (!ok && errno == EPIPE) {
        const timespec zero{0, 0};
        sigtimedwait(&pipe_set, nullptr, &zero);
    }
    pthread_sigmask(SIG_SETMASK, &old_set, nullptr);
    return ok;
}

}  // namespace

MovieEncoder::MovieEncoder(fs::path path, int width, int height, double fps)
    : m_path(std::move(path)),
      m_width(width),
      m_height(height) {
    if (width < 1 || height < 1 || !(fps > 0))
        throw InputError(m_path.string() + ": movie size " + std::to_string(width) + "x" +
                         std::to_string(height) + " at " + std::to_string(fps) +
                         " fps: expected a positive size and frame rate");
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) throw RuntimeError(m_path.string() + ": ffmpeg is not on PATH");
    m_tmp = m_path;
    m_tmp += ".tmp";
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.6g", fps);
    const std::string size = std::to_string(width) + "x" + std::to_string(height);
    // H.264 needs even dimensions for yuv420p: pad odd sizes by one pixel. -xerror: without it
    // ffmpeg 5.1 exits 0 when it cannot write the file's end (a full disk), leaving a broken movie
    const std::vector<std::string> args = {ffmpeg,
                                           "-hide_banner",
                                           "-loglevel",
                                           "error",
                                           "-xerror",
                                           "-nostdin",
                                           "-y",
                                           "-f",
                                           "rawvideo",
                                           "-pix_fmt",
                                           "rgba",
                                           "-s",
                                           size,
                                           "-framerate",
                                           rate,
                                           "-i",
                                           "pipe:0",
                                           "-vf",
                                           "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                           "-c:v",
                                           "libx264",
                                           "-preset",
                                           "veryfast",
                                           "-crf",
                                           "18",
                                           "-pix_fmt",
                                           "yuv420p",
                                           "-movflags",
                                           "+faststart",
                                           "-f",
                                           "mp4",
                                           m_tmp.string()};
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);

    int pipe_fd[2];
    if (pipe(pipe_fd) != 0)
        throw RuntimeError(m_path.string() + ": pipe() failed: " + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_fd[0], 0);
    posix_spawn_file_actions_addclose(&actions, pipe_fd[1]);
    posix_spawn_file_actions_addclose(&actions, pipe_fd[0]);
    // ffmpeg's own error lines go to a memory file, not the terminal: a failure is reported as
    // one line naming the movie, with ffmpeg's reason in it (a file would fail on a full disk)
    m_log_fd = ::memfd_create("ffmpeg-stderr", MFD_CLOEXEC);
    if (m_log_fd >= 0) posix_spawn_file_actions_adddup2(&actions, m_log_fd, 2);
    const int rc = posix_spawn(&m_pid, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fd[0]);
    if (rc != 0) {
        ::close(pipe_fd[1]);
        m_pid = -1;
        throw RuntimeError(m_path.string() + ": cannot start ffmpeg: " + std::strerror(rc));
    }
    m_fd = pipe_fd[1];
}

void MovieEncoder::add_frame(const RenderedImage& image) {
    if (image.width != m_width || image.height != m_height)
        throw InputError(m_path.string() + ": frame " + std::to_string(m_frames + 1) + " is " +
                         std::to_string(image.width) + "x" + std::to_string(image.height) +
                         ", expected " + std::to_string(m_width) + "x" + std::to_string(m_height));
    if (m_fd < 0 || !write_all(m_fd, image.rgba.data(), image.rgba.size()))
        throw RuntimeError(m_path.string() + ": ffmpeg stopped reading frames" + ffmpeg_reason());
    ++m_frames;
}

std::string MovieEncoder::ffmpeg_reason() {
    // ffmpeg's message is complete once it exited
    if (m_fd >= 0 || m_pid > 0) close_and_wait(nullptr);
    const std::string line = last_line_of(m_log_fd);
    return line.empty() ? std::string() : ": " + line;
}

void MovieEncoder::close_and_wait(int* status) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = -1;
    int st = -1;
    if (m_pid > 0) {
        while (waitpid(m_pid, &st, 0) < 0 && errno == EINTR) {
        }
    }
    m_pid = -1;
    if (status) *status = st;
}

void MovieEncoder::finish() {
    int status = -1;
    close_and_wait(&status);
    std::error_code ec;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || m_frames == 0) {
        fs::remove(m_tmp, ec);
        const std::string how = WIFEXITED(status)
                                    ? "exit code " + std::to_string(WEXITSTATUS(status))
                                : WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                                                      : "status " + std::to_string(status);
        throw RuntimeError(m_path.string() + ": ffmpeg failed (" + how + ", " +
                           std::to_string(m_frames) + " frames sent)" + ffmpeg_reason());
    }
    fs::rename(m_tmp, m_path, ec);
    if (ec) {
        fs::remove(m_tmp, ec);
        throw RuntimeError(m_path.string() + ": cannot move the movie into place: " + ec.message());
    }
    m_finished = true;
}

MovieEncoder::~MovieEncoder() {
    if (m_log_fd >= 0) ::close(m_log_fd);
    if (m_finished) return;
    if (m_pid > 0) kill(m_pid, SIGTERM);
    close_and_wait(nullptr);
    std::error_code ec;
    fs::remove(m_tmp, ec);
}

}  // namespace mudcrack
