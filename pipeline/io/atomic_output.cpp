#include "pipeline/io/atomic_output.h"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <system_error>
#include <thread>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

// the interrupt cleanup list
std::mutex g_cleanup_mutex;
std::set<fs::path>& cleanup_paths() {
    static std::set<fs::path> paths;
    return paths;
}

// what write_atomically appends to a file's name while writing it
std::string& temporary_suffix() {
    static std::string suffix = ".tmp";
    return suffix;
}

}  // namespace

void add_interrupt_cleanup(const fs::path& path) {
    const std::lock_guard<std::mutex> lock(g_cleanup_mutex);
    cleanup_paths().insert(path);
}

void remove_interrupt_cleanup(const fs::path& path) {
    const std::lock_guard<std::mutex> lock(g_cleanup_mutex);
    cleanup_paths().erase(path);
}

void run_interrupt_cleanup() {
    // the lock is kept: the process exits next, and a thread about to start a temporary file
    // waits in add_interrupt_cleanup instead of leaving it behind
    g_cleanup_mutex.lock();
    // A thread that registered its temporary file just before the lock can still create it, or
    // rename it into place, while remove_all empties its folder; the folder's removal then fails
    // (not empty) and an empty .partial/ stays behind. So the removal is repeated until nothing
    // registered exists: once a folder is gone nothing can be created in it, and each thread
    // creates at most its one registered file before it waits on the lock. A folder's files come
    // after it in the set, so the reverse walk removes them first.
    constexpr int kRemovalRounds = 200;  // 1 ms apart: far longer than a file's creation
    const std::set<fs::path>& paths = cleanup_paths();
    for (int round = 0; round < kRemovalRounds; ++round) {
        bool any_left = false;
        for (auto it = paths.rbegin(); it != paths.rend(); ++it) {
            std::error_code ec;
            fs::remove_all(*it, ec);
            any_left = any_left || fs::exists(fs::symlink_status(*it, ec));
        }
        if (!any_left) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    cleanup_paths().clear();
}

void set_temporary_suffix(const std::string& suffix) { temporary_suffix() = suffix; }

void write_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
    fs::path tmp = path;
    tmp += temporary_suffix();
    add_interrupt_cleanup(tmp);
    try {
        write(tmp);
    } catch (...) {
        std::error_code ec;
        fs::remove(tmp, ec);
        remove_interrupt_cleanup(tmp);
        throw;
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    remove_interrupt_cleanup(tmp);
    if (ec) {
        const std::string reason = ec.message();
        fs::remove(tmp, ec);
        throw RuntimeError(path.string() +
                           ": cannot rename the finished file into place: " + reason);
    }
}

std::string write_error_reason() {
    return errno != 0 ? std::string(std::strerror(errno)) : std::string("write failed");
}

void write_text_atomically(const fs::path& path, const std::string& text) {
    write_atomically(path, [&](const fs::path& tmp) {
        errno = 0;
        std::ofstream os(tmp, std::ios::binary);
        if (!os)
            throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
        os << text;
        os.close();  // the last buffer reaches the disk here: a full disk shows up at close
        if (!os) throw RuntimeError(tmp.string() + ": cannot write: " + write_error_reason());
    });
}

StagingDir::StagingDir(fs::path final_dir, bool keep_partial)
    : m_final(std::move(final_dir)),
      m_keep_partial(keep_partial) {
    const fs::path parent = m_final.parent_path().empty() ? fs::path(".") : m_final.parent_path();
    m_partial = parent / ("." + m_final.filename().string() + ".partial");
    if (!m_keep_partial) add_interrupt_cleanup(m_partial);
    std::error_code ec;
    fs::remove_all(m_partial, ec);
    fs::create_directories(m_partial, ec);
    if (ec)
        throw RuntimeError(m_partial.string() +
                           ": cannot create the output folder: " + ec.message());
}

StagingDir::~StagingDir() {
    remove_interrupt_cleanup(m_partial);
    if (m_committed || m_keep_partial) return;
    std::error_code ec;
    fs::remove_all(m_partial, ec);
}

void StagingDir::commit() {
    std::error_code ec;
    fs::remove_all(m_final, ec);
    fs::rename(m_partial, m_final, ec);
    if (!ec) remove_interrupt_cleanup(m_partial);
    if (ec)
        throw RuntimeError(m_final.string() +
                           ": cannot move the finished output into place: " + ec.message());
    m_committed = true;
}

}  // namespace mudcrack
