// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace ido {

/// Writes a file so that it appears whole or not at all: @p write_body fills a temporary
/// file in the target's folder, which is flushed, closed and renamed over @p path. If
/// @p write_body throws or the stream fails, the temporary is removed, any old file at
/// @p path stays untouched, and ido::IoError (naming @p path) is thrown. The temporary is
/// registered for removal by the signal cleanup (install_signal_cleanup) while it exists.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write_body,
                           bool binary = true);

/// Same, for writers that need a file name (e.g. ITK): @p write_to receives the temporary
/// path, which keeps @p path's extension (e.g. ".tmp-1234-out.nii.gz").
void write_path_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path&)>& write_to);

// ---- temporary files and fatal signals -----------------------------------------------------

/// Capacity of the registry of live temporary files (a fixed table: the signal handler reads
/// it without locks or allocation).
inline constexpr int kMaxTemporaryFiles = 64;

/// Registers @p path (made absolute) as a temporary file that a fatal signal must remove.
/// Returns a handle for unregister_temporary_file, or -1 when the table is full or the path
/// is longer than PATH_MAX (the file is then simply not guarded). Thread-safe, lock-free.
int register_temporary_file(const std::filesystem::path& path) noexcept;

/// Same for a folder: a fatal signal removes the files in it (not sub-folders) and then the
/// folder. For a batch of many outputs, whose temporaries would not fit the table one by one.
int register_temporary_folder(const std::filesystem::path& path) noexcept;

/// Forgets the file or folder of @p handle (does not remove it): call after it was renamed
/// into place or removed. A handle of -1 is ignored.
void unregister_temporary_file(int handle) noexcept;

/// How many temporary files and folders are registered now (for tests and diagnostics).
[[nodiscard]] int registered_temporary_file_count() noexcept;

/// Installs a handler for SIGINT, SIGTERM and SIGHUP that removes every registered
/// temporary file and folder and then re-raises the signal with its default action, so the process ends
/// as killed by it (exit status 128 + signal in a shell). A signal whose disposition is
/// "ignore" at the call (e.g. under nohup) stays ignored. The handler is async-signal-safe
/// (unlink, sigaction, sigprocmask, raise on a fixed table); a signal arriving while a
/// FileBatch commits waits until the renames are done. Call once, early in main().
void install_signal_cleanup();

/// The outputs of one run, written all or none: stage() gives the path to write instead of a
/// target — the target's file name inside a hidden staging folder (`.tmp-<pid>-<n>-batch`)
/// in the target's folder, one per folder and batch, registered for signal cleanup, so that
/// any number of outputs is guarded; commit() renames every staged file that exists into
/// place, with fatal signals held back until the last rename, and removes the staging
/// folders, so an interrupted run leaves either every output or none. A batch destroyed
/// uncommitted (an exception) removes its staging folders and what they hold.
class FileBatch {
 public:
  FileBatch() = default;
  FileBatch(const FileBatch&) = delete;
  FileBatch& operator=(const FileBatch&) = delete;
  ~FileBatch();
  /// @throws ido::IoError naming @p target when it is a folder or its folder does not exist.
  std::filesystem::path stage(const std::filesystem::path& target);
  /// The temporary staged for @p target, or an empty path if it was not staged.
  [[nodiscard]] std::filesystem::path staged(const std::filesystem::path& target) const;
  /// Renames the staged files into place (a staged file never written is skipped).
  /// @throws ido::IoError naming the target that could not be put in place.
  void commit();
  /// Removes every staged temporary without committing.
  void discard() noexcept;

 private:
  struct Entry {
    std::filesystem::path temporary, target;
  };
  struct Folder {
    std::filesystem::path target_folder, staging;
    int handle = -1;
  };
  std::vector<Entry> m_entries;
  std::vector<Folder> m_folders;
};

}  // namespace ido
