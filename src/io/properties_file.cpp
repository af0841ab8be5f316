#include "io/properties_file.hpp"

#include <yaml-cpp/yaml.h>

#include <set>

namespace rvc::io {

std::vector<engine::PropertySpec> load_properties(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw PropertiesError(path + ": cannot open the properties file");
  } catch (const YAML::ParserException& e) {
    throw PropertiesError(path + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                          ": " + e.msg);
  }
  auto where = [&](const YAML::Node& n) {
    return path + ":" + std::to_string(n.Mark().line + 1) + ":" + std::to_string(n.Mark().column + 1);
  };
  std::vector<engine::PropertySpec> out;
  YAML::Node list = root.IsMap() && root["properties"] ? root["properties"] : root;
  if (list.IsSequence()) {
    for (const auto& item : list) {
      engine::PropertySpec p;
      if (item.IsScalar()) {
        p.spec = item.as<std::string>();
      } else if (item.IsMap() && item["spec"]) {
        p.spec = item["spec"].as<std::string>();
        if (item["name"]) p.name = item["name"].as<std::string>();
      } else {
        throw PropertiesError(where(item) + ": each property needs a 'spec' (and a 'name')");
      }
      out.push_back(std::move(p));
    }
  } else if (list.IsMap()) {
    for (const auto& kv : list) {
      if (!kv.second.IsScalar())
        throw PropertiesError(where(kv.second) + ": expected 'name: spec' with the spec as a string");
      out.push_back({kv.first.as<std::string>(), kv.second.as<std::string>()});
    }
  } else {
    throw PropertiesError(path + ": expected a list of properties or a map from names to specs");
  }
  if (out.empty()) throw PropertiesError(path + ": no properties defined");
  std::set<std::string> names;
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i].name.empty()) out[i].name = "p" + std::to_string(i + 1);
    if (!names.insert(out[i].name).second) throw PropertiesError(path + ": duplicate property name '" + out[i].name + "'");
  }
  return out;
}

}  // namespace rvc::io
