#include "transport/rosbag2/bag_folder.hpp"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace rvc::transport {

namespace {
std::string scalar(const YAML::Node& n, const char* key) {
  const YAML::Node v = n[key];
  return v && v.IsScalar() ? v.as<std::string>() : "";
}

// What is wrong with a path that should be a regular file ("" if nothing):
// stat's own words for a symlink loop or a missing target, never an
// exception (std::filesystem's throwing calls ended the run uncaught).
std::string not_a_file(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) return std::strerror(errno);
  if (S_ISDIR(st.st_mode)) return "it is a folder, not a file";
  if (!S_ISREG(st.st_mode)) return "it is not a regular file";
  return "";
}
}  // namespace

bool names_entry(const std::string& path) {
  struct stat st{};
  return ::lstat(path.c_str(), &st) == 0;  // the entry itself: a dangling link or a loop is there too
}

BagMetadata read_bag_metadata(const std::string& dir) {
  const std::string file = (std::filesystem::path(dir) / "metadata.yaml").string();
  if (const std::string why = not_a_file(file); !why.empty())
    throw BagError("bag '" + dir + "': cannot read " + file + ": " + why);
  BagMetadata md;
  YAML::Node root;
  try {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) throw BagError("bag '" + dir + "': cannot read " + file + ": " + std::strerror(errno));
    root = YAML::Load(text.str());
  } catch (const YAML::ParserException& e) {
    throw BagError("bag '" + dir + "': metadata.yaml:" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  } catch (const YAML::Exception& e) {
    throw BagError("bag '" + dir + "': cannot read metadata.yaml: " + e.what());
  }
  const YAML::Node info = root.IsMap() ? root["rosbag2_bagfile_information"] : YAML::Node();
  if (!info || !info.IsMap())
    throw BagError("bag '" + dir + "': metadata.yaml has no map 'rosbag2_bagfile_information': not a rosbag2 bag");
  try {
    md.storage = scalar(info, "storage_identifier");
    md.compression_format = scalar(info, "compression_format");
    md.compression_mode = scalar(info, "compression_mode");
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0)
      throw BagError("bag '" + dir + "': metadata.yaml lists no storage file (relative_file_paths)");
    for (const auto& p : paths) {
      const std::string rel = p.as<std::string>();
      // rosbag2 writes names relative to the folder; older versions wrote
      // the folder's name in front ("bag/bag_0.db3"): take the file's name then.
      std::filesystem::path full = std::filesystem::path(dir) / rel;
      if (!names_entry(full.string())) full = std::filesystem::path(dir) / std::filesystem::path(rel).filename();
      if (!names_entry(full.string()))
        throw BagError("bag '" + dir + "': metadata.yaml lists '" + rel + "', which is not in the folder");
      if (const std::string why = not_a_file(full.string()); !why.empty())
        throw BagError("bag '" + dir + "': metadata.yaml lists '" + rel + "', which cannot be read: " + full.string() +
                       ": " + why);
      md.files.push_back(full.string());
    }
    if (const YAML::Node topics = info["topics_with_message_count"]; topics && topics.IsSequence())
      for (const auto& t : topics) {
        const YAML::Node meta = t["topic_metadata"];
        if (!meta || !meta.IsMap()) continue;
        BagTopicInfo ti;
        ti.name = scalar(meta, "name");
        ti.type = scalar(meta, "type");
        ti.encoding = scalar(meta, "serialization_format");
        if (!ti.name.empty()) md.topics.push_back(std::move(ti));
      }
  } catch (const YAML::Exception& e) {
    throw BagError("bag '" + dir + "': metadata.yaml:" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return md;
}

MergedBag::MergedBag(const std::string& path, std::vector<std::unique_ptr<BagReader>> parts) : BagReader(path) {
  for (auto& r : parts) parts_.push_back(Part{std::move(r), {}, false, false});
}

bool MergedBag::next(BagMessage& m) {
  // Fill the heads: every part once at the start, then only the part whose
  // message went out (the others' messages stay valid: nothing read them on).
  for (size_t i = 0; i < parts_.size(); ++i) {
    Part& p = parts_[i];
    if (p.started && i != last_) continue;
    p.started = true;
    if (!on_skip_) {
      p.reader->on_skip({});
    } else {  // a reason names the file of the folder it is in
      const std::string file = std::filesystem::path(p.reader->path()).filename().string();
      p.reader->on_skip([this, file](const std::string& why) { skipped(file + ": " + why); });
    }
    p.has = p.reader->next(p.head);
  }
  size_t best = SIZE_MAX;
  for (size_t i = 0; i < parts_.size(); ++i)
    if (parts_[i].has && (best == SIZE_MAX || parts_[i].head.log_time < parts_[best].head.log_time)) best = i;
  last_ = best;
  if (best == SIZE_MAX) return false;
  m = parts_[best].head;
  m.index = ++index_;
  return true;
}

}  // namespace rvc::transport
