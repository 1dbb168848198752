#pragma once
/// Atomic outputs (docs/architecture.md §3): make trusts mtimes, so a stage never leaves a
/// half-written file or folder where a complete one is expected. Files go through `name.tmp` +
/// rename; a stage's whole output folder is built as `.<name>.partial/` next to it and renamed on
/// success.
#include <filesystem>
#include <functional>
#include <string>

namespace mudcrack {

/// Writes `path` by calling write(tmp_path) and renaming tmp_path to path when it returns.
/// If write throws, the temporary file is removed and the exception propagates. While it is
/// written, tmp_path is on the interrupt cleanup list (below).
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& tmp)>& write);

/// Sets what write_atomically appends to a name while it writes (".tmp" unless set). A writer
/// that shares its folder with others (a farm chunk under a shared StageLock) makes it unique,
/// e.g. ".<host>.<pid>.tmp", so two chunks given the same frame never write one temporary file.
/// Call before any thread writes.
void set_temporary_suffix(const std::string& suffix);

/// Why the write that just failed failed: strerror(errno) ("No space left on device", "File too
/// large", "Read-only file system"), or "write failed" when errno holds nothing. Callers zero errno
/// before writing, so an old errno is not blamed.
/// @note C++ streams do not promise to keep errno, but libstdc++'s filebuf leaves the failed
/// write()'s errno in place, which is all a one-line error report needs.
std::string write_error_reason();

/// Writes a whole text file atomically.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

/// What a stage stopped by SIGTERM or SIGINT must not leave behind: the `.partial/` folders and
/// temporary files being written, registered while they exist. stage_cli's signal handling calls
/// run_interrupt_cleanup() and exits 128 + the signal number (docs/architecture.md §3, §5).
/// Thread-safe.
void add_interrupt_cleanup(const std::filesystem::path& path);
void remove_interrupt_cleanup(const std::filesystem::path& path);
/// Removes every registered path (files and whole folders); errors are ignored. For a process
/// about to exit: the list stays locked, so no thread starts another temporary file.
void run_interrupt_cleanup();

/// A stage's output folder under construction. The constructor makes a fresh
/// `<parent>/.<name>.partial/`; commit() replaces `<parent>/<name>/` with it; destruction without
/// commit() deletes it unless keep_partial was set (a TD inspecting a failed run).
class StagingDir {
public:
    explicit StagingDir(std::filesystem::path final_dir, bool keep_partial = false);
    ~StagingDir();
    StagingDir(const StagingDir&) = delete;
    StagingDir& operator=(const StagingDir&) = delete;

    const std::filesystem::path& path() const { return m_partial; }
    const std::filesystem::path& final_path() const { return m_final; }
    void commit();

private:
    std::filesystem::path m_final;
    std::filesystem::path m_partial;
    bool m_keep_partial;
    bool m_committed = false;
};

}  // namespace mudcrack
