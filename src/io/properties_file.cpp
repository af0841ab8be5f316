#include "io/properties_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <set>

namespace rvc::io {
namespace {

// Both entry points: the properties, and (if `levels` is given) the `level:`
// of those that have one.
std::vector<engine::PropertySpec> load(const std::string& path, std::vector<PropertyLevel>* levels) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAllFromFile(path);
  } catch (const YAML::BadFile&) {
    throw PropertiesError(path + ": cannot open the properties file");
  } catch (const YAML::ParserException& e) {
    throw PropertiesError(path + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                          ": " + e.msg);
  }
  auto where = [&](const YAML::Node& n) {
    return path + ":" + std::to_string(n.Mark().line + 1) + ":" + std::to_string(n.Mark().column + 1);
  };
  // Several YAML documents (---): silently reading only the first would drop
  // the others' properties.
  if (documents.size() > 1)
    throw PropertiesError(where(documents[1]) + ": a second YAML document starts here; put all properties in one "
                                                "document (no '---' between them)");
  if (documents.empty() || documents[0].IsNull()) throw PropertiesError(path + ": no properties defined");
  const YAML::Node& root = documents[0];
  auto text = [&](const YAML::Node& n, const char* what) {
    if (!n.IsScalar()) throw PropertiesError(where(n) + ": " + what + " must be a string, not a list or a map");
    return n.as<std::string>();
  };
  std::vector<engine::PropertySpec> out;
  YAML::Node list = root;
  if (root.IsMap() && root["properties"]) {
    for (const auto& kv : root)
      if (kv.first.as<std::string>() != "properties")
        throw PropertiesError(where(kv.first) + ": unknown key '" + kv.first.as<std::string>() +
                              "' next to 'properties' (the file holds only 'properties:')");
    list = root["properties"];
  }
  if (list.IsSequence()) {
    for (const auto& item : list) {
      engine::PropertySpec p;
      if (item.IsScalar()) {
        p.spec = item.as<std::string>();
      } else if (item.IsMap() && item["spec"]) {
        for (const auto& kv : item) {
          const std::string key = kv.first.as<std::string>();
          if (key != "name" && key != "spec" && key != "level")
            throw PropertiesError(where(kv.first) + ": unknown key '" + key +
                                  "' (a property has 'name', 'spec' and optionally 'level')");
        }
        p.spec = text(item["spec"], "'spec'");
        if (item["name"]) p.name = text(item["name"], "'name'");
        if (item["level"]) {
          // The /diagnostics level of a violation (rvc monitor --diagnostics).
          std::string level = text(item["level"], "'level'");
          for (char& c : level) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
          if (level != "warn" && level != "error")
            throw PropertiesError(where(item["level"]) + ": level '" + item["level"].as<std::string>() +
                                  "': expected warn or error");
          if (levels) levels->push_back({out.size(), level});
        }
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
  if (levels)
    for (auto& l : *levels) l.name = out[l.index].name;
  return out;
}

}  // namespace

std::vector<engine::PropertySpec> load_properties(const std::string& path) { return load(path, nullptr); }

std::vector<PropertyLevel> load_property_levels(const std::string& path) {
  std::vector<PropertyLevel> levels;
  load(path, &levels);
  return levels;
}

}  // namespace rvc::io
