// SPDX-License-Identifier: Apache-2.0
#include "ido/core/atomic_file.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <system_error>

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include "ido/core/error.h"

namespace ido {
namespace fs = std::filesystem;

// ---- the registry of temporary files --------------------------------------------------------
//
// A fixed table that the signal handler walks without locks or allocation. A slot moves
// Free -> Filling (its path being copied) -> LiveFile or LiveFolder -> Free when unregistered,
// or -> Taken when the handler claims it to remove its path (the process is ending then).
// Only the handler reads a path, and only of a slot it has claimed, so a path is never read
// while it is copied.
namespace {
enum SlotState : int { kFree = 0, kFilling = 1, kLiveFile = 2, kLiveFolder = 3, kTaken = 4 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

Slot g_slots[kMaxTemporaryFiles];

// Commits in progress (> 0), or -1 once a fatal signal is being acted on.
std::atomic<int> g_commits{0};
// The fatal signal that arrived during a commit, acted on when the last commit ends.
std::atomic<int> g_pending_signal{0};

/// Removes the files of a folder, then the folder, with system calls only (getdents64 into a
/// static buffer: only one thread gets here, see on_fatal_signal). A pass that removes
/// entries is followed by another, since removing while listing may skip some.
void remove_folder(const char* path) noexcept {
  alignas(struct dirent64) static char buffer[8192];
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    for (int pass = 0; pass < 16; ++pass) {
      bool removed = false;
      ::lseek(fd, 0, SEEK_SET);
      for (;;) {
        const ssize_t n = ::getdents64(fd, buffer, sizeof buffer);
        if (n <= 0) break;
        for (ssize_t at = 0; at < n;) {
          const auto* entry = reinterpret_cast<const struct dirent64*>(buffer + at);
          const char* name = entry->d_name;
          const bool dots = name[0] == '.' && (name[1] == '\0' || (name[1] == '.' && name[2] == '\0'));
          if (!dots && ::unlinkat(fd, name, 0) == 0) removed = true;
          at += entry->d_reclen;
        }
      }
      if (!removed) break;
    }
    ::close(fd);
  }
  ::rmdir(path);
}

void unlink_registered() noexcept {
  // Files first (some may lie in a registered folder), then folders.
  for (const int live : {kLiveFile, kLiveFolder})
    for (auto& slot : g_slots) {
      int expected = live;
      if (!slot.state.compare_exchange_strong(expected, kTaken)) continue;
      if (live == kLiveFolder)
        remove_folder(slot.path);
      else
        ::unlink(slot.path);
    }
}

/// Removes the temporaries, then ends the process by @p sig with its default action.
/// Async-signal-safe.
void die_by(int sig) noexcept {
  unlink_registered();
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, sig);
  ::sigprocmask(SIG_UNBLOCK, &set, nullptr);
  ::raise(sig);
}

extern "C" void on_fatal_signal(int sig) {
  const int saved_errno = errno;
  g_pending_signal.store(sig);
  int idle = 0;
  // No commit running: act now. Otherwise the last commit to end acts on g_pending_signal.
  if (g_commits.compare_exchange_strong(idle, -1)) die_by(sig);
  errno = saved_errno;
}

/// Holds fatal signals back (on every thread) while a batch of renames runs.
class SignalHold {
 public:
  SignalHold() noexcept {
    for (;;) {
      int n = g_commits.load();
      if (n < 0)
        for (;;) ::pause();  // a signal is ending the process on another thread
      if (g_commits.compare_exchange_weak(n, n + 1)) break;
    }
  }
  ~SignalHold() {
    if (g_commits.fetch_sub(1) != 1) return;
    const int sig = g_pending_signal.load();
    int idle = 0;
    if (sig != 0 && g_commits.compare_exchange_strong(idle, -1)) die_by(sig);
  }
  SignalHold(const SignalHold&) = delete;
  SignalHold& operator=(const SignalHold&) = delete;
};

/// Unregisters a temporary file when it goes out of scope.
struct Registration {
  int handle;
  explicit Registration(const fs::path& path) noexcept : handle(register_temporary_file(path)) {}
  ~Registration() { unregister_temporary_file(handle); }
  Registration(const Registration&) = delete;
  Registration& operator=(const Registration&) = delete;
};

fs::path temp_sibling(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  // Keep the full file name as the suffix so extension-driven writers (ITK) still work.
  return dir / fmt::format(".tmp-{}-{}-{}", static_cast<long>(::getpid()), counter++,
                           path.filename().string());
}

void check_target(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path.string(), "is a folder, expected a file");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw IoError(path.string(), fmt::format("folder '{}' does not exist", dir.string()));
}

void commit(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw IoError(path.string(), "cannot rename temporary file into place");
  }
}
}  // namespace

namespace {
int register_path(const fs::path& path, bool folder) noexcept {
  std::string absolute;
  try {
    absolute = fs::absolute(path).string();
  } catch (...) {
    return -1;
  }
  if (absolute.size() >= sizeof(Slot::path)) return -1;
  for (int i = 0; i < kMaxTemporaryFiles; ++i) {
    int expected = kFree;
    if (g_slots[i].state.compare_exchange_strong(expected, kFilling)) {
      std::memcpy(g_slots[i].path, absolute.c_str(), absolute.size() + 1);
      g_slots[i].state.store(folder ? kLiveFolder : kLiveFile);
      return i;
    }
  }
  return -1;
}
}  // namespace

int register_temporary_file(const fs::path& path) noexcept { return register_path(path, false); }

int register_temporary_folder(const fs::path& path) noexcept { return register_path(path, true); }

void unregister_temporary_file(int handle) noexcept {
  if (handle < 0 || handle >= kMaxTemporaryFiles) return;
  // A slot the handler has taken stays taken: the process is ending.
  for (const int live : {kLiveFile, kLiveFolder}) {
    int expected = live;
    if (g_slots[handle].state.compare_exchange_strong(expected, kFree)) return;
  }
}

int registered_temporary_file_count() noexcept {
  int n = 0;
  for (const auto& slot : g_slots) {
    const int state = slot.state.load();
    n += state == kLiveFile || state == kLiveFolder ? 1 : 0;
  }
  return n;
}

void install_signal_cleanup() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    struct sigaction act {};
    act.sa_handler = on_fatal_signal;
    sigemptyset(&act.sa_mask);
    // While one is handled the others wait (they would end the process the same way).
    for (const int other : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&act.sa_mask, other);
    act.sa_flags = SA_RESTART;
    ::sigaction(sig, &act, nullptr);
  }
}

// ---- atomic writes ------------------------------------------------------------------------

void write_file_atomically(const fs::path& path,
                           const std::function<void(std::ostream&)>& write_body, bool binary) {
  check_target(path);
  const fs::path tmp = temp_sibling(path);
  const Registration guard(tmp);  // before the file exists, so no moment leaves it unguarded
  try {
    {
      std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      if (!out) throw IoError(path.string(), "cannot open for writing");
      write_body(out);
      out.flush();
      if (!out) throw IoError(path.string(), "write failed (disk full or I/O error?)");
    }
    commit(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void write_path_atomically(const fs::path& path,
                           const std::function<void(const fs::path&)>& write_to) {
  check_target(path);
  const fs::path tmp = temp_sibling(path);
  const Registration guard(tmp);
  try {
    write_to(tmp);
    std::error_code ec;
    if (!fs::exists(tmp, ec)) throw IoError(path.string(), "writer produced no file");
    commit(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

// ---- FileBatch ------------------------------------------------------------------------------

FileBatch::~FileBatch() { discard(); }

fs::path FileBatch::stage(const fs::path& target) {
  check_target(target);
  if (auto existing = staged(target); !existing.empty()) return existing;
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  auto it = std::find_if(m_folders.begin(), m_folders.end(), [&](const Folder& f) {
    return f.target_folder.lexically_normal() == folder.lexically_normal();
  });
  if (it == m_folders.end()) {
    Folder f{folder, temp_sibling(folder / "batch"), -1};
    f.handle = register_temporary_folder(f.staging);  // before it exists
    std::error_code ec;
    if (!fs::create_directory(f.staging, ec)) {
      unregister_temporary_file(f.handle);
      throw IoError(target.string(), fmt::format("cannot create a staging folder in '{}'", folder.string()));
    }
    m_folders.push_back(std::move(f));
    it = m_folders.end() - 1;
  }
  m_entries.push_back({it->staging / target.filename(), target});
  return m_entries.back().temporary;
}

fs::path FileBatch::staged(const fs::path& target) const {
  const fs::path want = target.lexically_normal();
  for (const auto& e : m_entries)
    if (e.target.lexically_normal() == want) return e.temporary;
  return {};
}

void FileBatch::commit() {
  const SignalHold hold;
  while (!m_entries.empty()) {
    const Entry& e = m_entries.front();
    std::error_code ec;
    if (fs::exists(e.temporary, ec)) {  // a staged output left unwritten is skipped
      fs::rename(e.temporary, e.target, ec);
      if (ec) throw IoError(e.target.string(), "cannot rename the temporary file into place");
    }
    m_entries.erase(m_entries.begin());
  }
  discard();  // the staging folders, now empty
}

void FileBatch::discard() noexcept {
  m_entries.clear();
  for (auto& f : m_folders) {
    std::error_code ec;
    fs::remove_all(f.staging, ec);
    unregister_temporary_file(f.handle);
  }
  m_folders.clear();
}

}  // namespace ido
