#include "pipeline/io/stage_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

constexpr int kLockAttempts = 8;  // a lock file removed under us by its last holder: try again

std::string utc_now() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
    return text;
}

// whether fd is still the file at path (a releasing holder may have removed it meanwhile)
bool is_same_file(int fd, const fs::path& path) {
    struct stat open_file {
    }, named{};
    if (fstat(fd, &open_file) != 0 || stat(path.c_str(), &named) != 0) return false;
    return open_file.st_dev == named.st_dev && open_file.st_ino == named.st_ino;
}

// the refusal: who holds the folder, read from the lock file (an exclusive holder) or known from
// the mode (chunks share it)
std::string refusal(const fs::path& stage_dir, const fs::path& lock_path,
                    const std::string& program, int fd) {
    std::string holder;
    if (flock(fd, LOCK_SH | LOCK_NB) == 0) {  // only sharing chunks hold it
        flock(fd, LOCK_UN);
        holder = "farm chunks (mc-render --frames) are writing into it";
    } else {
        const std::string recorded = lock_holder_text(lock_path);
        holder = "another writer holds it (" +
                 (recorded.empty() ? std::string("no holder recorded") : recorded) + ")";
    }
    return stage_dir.string() + ": " + holder + "; lock " + lock_path.string() + ": " + program +
           " refuses to write into a folder another run is writing (one writer per folder): wait for that run "
           "or stop it; a lock whose holder died is released by the system";
}

}  // namespace

std::string lock_host_name() {
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) != 0) return "unknown";
    return name;
}

std::string lock_holder_text(const fs::path& lock_file) {
    std::ifstream is(lock_file);
    std::string line, host, pid, program, start;
    while (std::getline(is, line)) {
        const size_t eq = line.find('=');
        if (eq == std::string::npos) continue;
        const std::string key = line.substr(0, eq), value = line.substr(eq + 1);
        if (key == "host") host = value;
        if (key == "pid") pid = value;
        if (key == "program") program = value;
        if (key == "start") start = value;
    }
    if (pid.empty()) return "";
    return "host " + host + ", pid " + pid + ", " + program + ", since " + start;
}

StageLock::StageLock(const fs::path& stage_dir, const std::string& program, LockMode mode)
    : m_mode(mode) {
    // a stage writes only into a folder of its own: through a link it would delete and replace
    // another folder's files (another shot's, under /reuse), so a linked stage folder is refused,
    // never followed or replaced (readers follow links: /reuse shares a stage that way)
    std::error_code ec;
    if (fs::is_symlink(stage_dir, ec))
        throw InputError(stage_dir.string() + ": a symbolic link (to " +
                         fs::read_symlink(stage_dir, ec).string() + "): " + program +
                         " writes only into a real folder, never through a link into another one: "
                         "remove the link, or give --out a folder of its own");
    m_stage_dir = fs::weakly_canonical(fs::absolute(stage_dir), ec);
    if (ec) m_stage_dir = fs::absolute(stage_dir).lexically_normal();
    const fs::path parent = m_stage_dir.parent_path();
    m_path = parent / ("." + m_stage_dir.filename().string() + ".lock");
    // the folders made here go again on release when nothing else was written into them
    for (fs::path p = parent; !p.empty() && !fs::exists(p, ec) && p != p.parent_path();
         p = p.parent_path())
        m_made_dirs.push_back(p);
    fs::create_directories(parent, ec);
    if (ec)
        throw RuntimeError(parent.string() + ": cannot create the output folder: " + ec.message());

    for (int attempt = 0; attempt < kLockAttempts; ++attempt) {
        const int fd = open(m_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0)
            throw RuntimeError(m_path.string() +
                               ": cannot create the lock file: " + std::strerror(errno));
        if (flock(fd, (mode == LockMode::Exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
            const std::string why = refusal(m_stage_dir, m_path, program, fd);
            close(fd);
            throw InputError(why);
        }
        if (!is_same_file(fd, m_path)) {  // its last holder removed it before we locked it
            close(fd);
            continue;
        }
        m_fd = fd;
        break;
    }
    if (m_fd < 0)
        throw RuntimeError(m_path.string() +
                           ": cannot take the lock: the file keeps being replaced");
    if (mode == LockMode::Exclusive) {
        std::ostringstream record;
        record << "host=" << lock_host_name() << "\npid=" << getpid() << "\nprogram=" << program
               << "\nstart=" << utc_now() << "\n";
        const std::string text = record.str();
        // the record only helps a refused writer name the holder: a failed write is not fatal
        [[maybe_unused]] const bool is_recorded =
            ftruncate(m_fd, 0) == 0 &&
            write(m_fd, text.data(), text.size()) == ssize_t(text.size());
    }
}

StageLock::~StageLock() { release(); }

void StageLock::release() {
    const int fd = m_fd.exchange(-1);
    if (fd < 0) return;
    // the last holder removes the file: an exclusive lock means no one shares it now
    if (m_mode == LockMode::Exclusive || flock(fd, LOCK_EX | LOCK_NB) == 0) {
        if (is_same_file(fd, m_path)) unlink(m_path.c_str());
    }
    close(fd);
    std::error_code ec;
    for (const fs::path& p : m_made_dirs)
        if (fs::is_empty(p, ec)) fs::remove(p, ec);
}

}  // namespace mudcrack
