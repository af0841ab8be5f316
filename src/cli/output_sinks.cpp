#include "cli/output_sinks.hpp"

#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "cli/commands.hpp"

namespace rvc::cli {

int open_outputs(const std::vector<std::string>& uris, const transport::TransportOptions& transports,
                 size_t wait_subscribers, double wait_timeout, const char* who,
                 std::vector<std::unique_ptr<transport::Sink>>& sinks) {
  for (const auto& uri : uris) sinks.push_back(transport::open_sink(uri, transports));
  for (size_t i = 0; i < sinks.size() && wait_subscribers > 0; ++i) {
    if (transport::scheme_of(uris[i]) == "file" || transport::scheme_of(uris[i]) == "mcap") continue;  // no subscribers
    std::fprintf(stderr, "rvc %s: waiting for %zu subscriber%s on %s ...\n", who, wait_subscribers,
                 wait_subscribers == 1 ? "" : "s", uris[i].c_str());
    if (!sinks[i]->wait_matched(wait_subscribers, std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)))) {
      std::fprintf(stderr, "rvc: no subscriber matched on %s within %.1f s (--wait-timeout)\n", uris[i].c_str(),
                   wait_timeout);
      if (!sinks[i]->discovery().empty())
        std::fprintf(stderr, "rvc: this publisher: %s\n", sinks[i]->discovery().c_str());
      return kIncomplete;
    }
  }
  return 0;
}

int refuse_input_copies(const std::vector<std::string>& outputs, const std::string& input) {
  for (const auto& uri : outputs)
    if (uri.rfind("mcap:", 0) == 0 && (uri.ends_with("?inputs=1") || uri.ends_with("?inputs=true"))) {
      std::fprintf(stderr,
                   "rvc: %s copies the messages of a ROS 2 bag (rvc check BAG, --input bag:BAG); the messages of %s "
                   "are not copied: drop ?inputs=1 (docs/mcap-output.md)\n",
                   uri.c_str(), input.c_str());
      return kUsage;
    }
  return 0;
}

std::string written_file(const std::string& uri) {
  if (uri.empty() || uri == "-") return "";
  if (uri.rfind("sqlite:", 0) == 0) return uri.substr(7);
  if (uri.rfind("postgres", 0) == 0) return "";
  std::string scheme;
  try {
    scheme = transport::scheme_of(uri);
  } catch (const std::invalid_argument&) {
    return "";  // refused when it is opened, with its own reason
  }
  if (scheme == "file") return uri.rfind("file:", 0) == 0 ? uri.substr(5) : uri;
  if (scheme == "mcap") {
    std::string path = uri.substr(uri.find(':') + 1);
    if (const size_t q = path.rfind("?inputs="); q != std::string::npos) path.resize(q);  // an output's option
    return path;
  }
  return "";
}

namespace {

// Where writing a file that does not exist yet creates it: a dangling
// symlink is followed to its target, then the path is made absolute with its
// existing part resolved.
std::filesystem::path where_written(const std::string& path, std::error_code& ec) {
  namespace fs = std::filesystem;
  fs::path p = fs::absolute(path, ec);
  std::error_code absent;  // (no such file: nothing to follow)
  for (int hops = 0; !ec && hops < 40 && fs::is_symlink(fs::symlink_status(p, absent)); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return ec ? p : fs::weakly_canonical(p, ec);
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  const bool ea = ::stat(a.c_str(), &sa) == 0, eb = ::stat(b.c_str(), &sb) == 0;
  // Two writers on one device (/dev/null, a terminal) do not corrupt a file.
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino && S_ISREG(sa.st_mode);
  if (ea != eb) return false;
  std::error_code ec1, ec2;
  const auto ca = where_written(a, ec1), cb = where_written(b, ec2);
  return !ec1 && !ec2 ? ca == cb : a == b;
}

}  // namespace

int refuse_shared_files(const std::vector<std::pair<std::string, std::string>>& targets) {
  for (size_t i = 0; i < targets.size(); ++i) {
    const std::string fi = written_file(targets[i].second);
    if (fi.empty()) continue;
    for (size_t j = i + 1; j < targets.size(); ++j) {
      const std::string fj = written_file(targets[j].second);
      if (fj.empty() || !same_file(fi, fj)) continue;
      std::fprintf(stderr, "rvc: %s '%s' and %s '%s' name the same file: each would overwrite the other; give "
                           "each output a file of its own\n",
                   targets[i].first.c_str(), targets[i].second.c_str(), targets[j].first.c_str(),
                   targets[j].second.c_str());
      return kUsage;
    }
  }
  return 0;
}

}  // namespace rvc::cli
