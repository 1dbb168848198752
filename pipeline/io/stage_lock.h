#pragma once
/// One writer per output folder (docs/architecture.md §3): a stage locks its folder
/// OUT/<shot>/<stage>/ before it writes anything, through the file OUT/<shot>/.<stage>.lock, and
/// refuses a stage folder that is a symbolic link (it would write into another folder). The lock
/// is flock(2)'s, so the kernel
/// drops it when its holder dies however it dies (SIGKILL, a crash): a lock left by a dead
/// process is no lock, and the next run takes it. An exclusive holder records its host, pid,
/// program and start time in the file, and a refused writer names them.
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

namespace mudcrack {

enum class LockMode {
    Exclusive,  // a whole stage run: no other writer of the folder
    Shared,     // a farm chunk writing its own frames (mc-render --frames): other chunks may run
};

/// Holds the lock of a stage folder while it lives; the lock file is removed on release when no
/// other holder shares it.
class StageLock {
public:
    /// Takes the lock of `stage_dir` for `program` ("mc-sim"), creating the folder's parent when
    /// it is missing (and removing it on release if it is still empty), without waiting.
    /// @throws InputError naming the folder and the holder (host, pid, program, start time) when
    ///         another live writer holds it, or naming the link when the folder is a symbolic
    ///         link; RuntimeError when the lock file cannot be made
    StageLock(const std::filesystem::path& stage_dir, const std::string& program, LockMode mode);
    ~StageLock();
    StageLock(const StageLock&) = delete;
    StageLock& operator=(const StageLock&) = delete;

    /// The stage folder the lock covers, absolute (links in the folders above it resolved).
    const std::filesystem::path& stage_dir() const { return m_stage_dir; }
    const std::filesystem::path& lock_path() const { return m_path; }
    LockMode mode() const { return m_mode; }
    /// Unlocks (and removes the lock file when no one shares it); called by the destructor, and by
    /// the interrupt handling before it exits.
    void release();

private:
    std::filesystem::path m_stage_dir;
    std::filesystem::path m_path;
    LockMode m_mode;
    std::atomic<int> m_fd{-1};  // atomic: the signal handling may release it from another thread
    std::vector<std::filesystem::path> m_made_dirs;  // made for the lock file, innermost first
};

/// This machine's name, as a lock records it.
std::string lock_host_name();

/// The holder a lock file records ("host h, pid 123, mc-sim, since 2026-11-25 17:30:02 UTC"), or
/// "" when it records none.
std::string lock_holder_text(const std::filesystem::path& lock_file);

}  // namespace mudcrack
