#include "app/OutputFolder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <string_view>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/Error.hpp"

namespace fountain {

namespace fs = std::filesystem;

namespace {

std::string read_all(int fd) {
  std::string text;
  char buf[256];
  ::lseek(fd, 0, SEEK_SET);
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0 && text.size() < 4096;) text.append(buf, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
  return text;
}

std::string this_host() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

bool same_file(int fd, const std::string& path) {
  struct stat a {}, b {};
  return ::fstat(fd, &a) == 0 && ::stat(path.c_str(), &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

}  // namespace

OutputFolderLock::OutputFolderLock(const std::string& directory) : path_((fs::path(directory) / kFileName).string()) {
  // A holder that releases the lock unlinks the file first: a lock taken on an unlinked file
  // is retried on the file now at the path.
  for (int attempt = 0; attempt < 100; ++attempt) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw InputError(fmt::format("output directory '{}': cannot create the lock file {}: {}", directory, path_,
                                   std::strerror(errno)));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      const std::string holder = read_all(fd_);
      ::close(fd_);
      fd_ = -1;
      if (err == EWOULDBLOCK)
        throw InputError(fmt::format("output directory '{}' is in use by another run ({}; lock file {}): wait for "
                                     "it to end, or give this run another output.directory",
                                     directory, holder.empty() ? "holder unknown" : holder, path_));
      // A file system without flock (some parallel ones are mounted so): the run goes on,
      // unguarded, and says so.
      unsupported_ = fmt::format("cannot lock {} ({}): nothing keeps a second run out of this folder", path_,
                                 std::strerror(err));
      if (holder.empty()) ::unlink(path_.c_str());  // the empty file this run made
      return;
    }
    if (same_file(fd_, path_)) break;
    ::close(fd_);
    fd_ = -1;
  }
  if (fd_ < 0) throw InputError(fmt::format("output directory '{}': cannot take the lock {}", directory, path_));
  stale_holder_ = read_all(fd_);
  const std::string me = fmt::format("PID {} on host {}\n", static_cast<long>(::getpid()), this_host());
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    const int err = errno;
    ::close(fd_);  // the destructor does not run for a constructor that throws
    fd_ = -1;
    throw InputError(fmt::format("output directory '{}': cannot write the lock file {}: {}", directory, path_,
                                 std::strerror(err)));
  }
}

OutputFolderLock::~OutputFolderLock() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());
  ::close(fd_);
}

namespace {

// Whether `name` matches `pattern`, in which '#' stands for one or more digits (std::regex
// would do, but GCC 12 warns inside it under the sanitizers).
bool matches_pattern(std::string_view name, std::string_view pattern) {
  if (pattern.empty()) return name.empty();
  if (pattern.front() != '#') return !name.empty() && name.front() == pattern.front() &&
                                    matches_pattern(name.substr(1), pattern.substr(1));
  std::size_t digits = 0;
  while (digits < name.size() && name[digits] >= '0' && name[digits] <= '9') ++digits;
  for (std::size_t k = digits; k >= 1; --k)
    if (matches_pattern(name.substr(k), pattern.substr(1))) return true;
  return false;
}

bool matches_any(std::string_view name, std::initializer_list<std::string_view> patterns) {
  return std::any_of(patterns.begin(), patterns.end(), [&](std::string_view p) { return matches_pattern(name, p); });
}

bool is_snapshot_name(const std::string& basename, const std::string& name) {
  return name.size() > basename.size() && name.compare(0, basename.size(), basename) == 0 &&
         matches_pattern(std::string_view(name).substr(basename.size()), "_#.hdf5");
}

bool is_restart_name(const std::string& name) { return matches_any(name, {"restart.hdf5", "restart_#_rank#.hdf5"}); }

bool is_dump_name(const std::string& name) {
  return matches_any(name, {"task_graph.dot", "task_graph_rank#.dot", "dependency_graph_#.csv", "timeline_step#.csv",
                            "timeline_step#_rank#.csv"});
}

// The group catalogues a comoving run may write beside its snapshots (output.fof_groups, hop_groups).
bool is_catalogue_name(const std::string& name) { return matches_any(name, {"fof_#.hdf5", "hop_#.hdf5"}); }

bool matches_output_name(const std::string& basename, const std::string& name) {
  return is_snapshot_name(basename, name) || is_restart_name(name) || is_dump_name(name) || is_catalogue_name(name) ||
         name == "statistics.txt";
}

fs::path canonical_or_normal(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

}  // namespace

bool is_run_output(const std::string& directory, const std::string& basename, const std::string& file) {
  const fs::path f = canonical_or_normal(file);
  return f.parent_path() == canonical_or_normal(directory) && matches_output_name(basename, f.filename().string());
}

std::vector<std::string> earlier_run_outputs(const std::string& directory, const std::string& basename) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(directory, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_snapshot_name(basename, name) || is_restart_name(name) || is_catalogue_name(name) || name == "statistics.txt")
      found.push_back(entry.path().string());
  }
  std::sort(found.begin(), found.end());
  return found;
}

void guard_output_folder(const std::string& directory, const std::string& basename,
                         const std::vector<std::string>& inputs, bool restart, bool overwrite) {
  for (const auto& in : inputs)
    if (is_run_output(directory, basename, in))
      throw InputError(fmt::format("{} is an input of this run, but the run writes a file of that name in its "
                                   "output directory '{}': move it, or change output.directory or output.basename",
                                   in, directory));
  if (restart) return;
  const std::vector<std::string> earlier = earlier_run_outputs(directory, basename);
  if (earlier.empty()) return;
  if (!overwrite) {
    std::string listed;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, earlier.size()); ++k)
      listed += (k ? ", " : "") + fs::path(earlier[k]).filename().string();
    if (earlier.size() > 3) listed += fmt::format(" and {} more", earlier.size() - 3);
    const bool resumable = std::any_of(earlier.begin(), earlier.end(), [](const std::string& f) {
      return fs::path(f).filename() == "restart.hdf5";
    });
    throw InputError(fmt::format("output directory '{}' holds an earlier run's files ({}){}: a fresh run would "
                                 "replace them; pass --overwrite to do so, or choose another output.directory",
                                 directory, listed, resumable ? "; to continue that run, pass --restart" : ""));
  }
  for (const auto& f : earlier) {
    std::error_code ec;
    fs::remove(f, ec);
    if (ec) throw InputError(fmt::format("{}: cannot remove it for --overwrite: {}", f, ec.message()));
  }
}

}  // namespace fountain
