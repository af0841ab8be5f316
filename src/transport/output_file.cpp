#include "transport/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/xattr.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rvc::transport {

std::string output_file_refusal(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "";  // not there (or unreachable: open says why)
  if (!S_ISREG(st.st_mode) || st.st_size == 0) return "";
  char mark[8];
  if (::getxattr(path.c_str(), kOutputMark, mark, sizeof mark) >= 0) return "";
  if (errno == ENOTSUP)
    return "it exists, and its file system keeps no extended attributes, so rvc cannot tell whether it "
           "wrote it: refusing to write over it (remove it or choose another path)";
  return "it exists and rvc did not write it: refusing to write over it (rvc writes over only the files "
         "it made; remove it or choose another path)";
}

std::FILE* open_output_file(const std::string& path, const std::string& what) {
  const std::string why = output_file_refusal(path);
  if (!why.empty()) throw std::invalid_argument(what + " '" + path + "': " + why);
  // O_TRUNC only now that the file is known to be new, empty, rvc's or not a regular file
  // (a device or pipe ignores it).
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::invalid_argument("cannot open '" + path + "' for writing: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
    // Best effort: without the mark (a file system with no user attributes) a later run refuses
    // this file instead of writing over it, which is the safe side.
    (void)::fsetxattr(fd, kOutputMark, "1", 1, 0);
  }
  std::FILE* f = ::fdopen(fd, "w");
  if (!f) {
    const int e = errno;
    ::close(fd);
    throw std::invalid_argument("cannot open '" + path + "' for writing: " + std::strerror(e));
  }
  return f;
}

}  // namespace rvc::transport
