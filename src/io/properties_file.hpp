// Loads named properties from a YAML or JSON file. Accepted shapes:
//   properties:                      # a list of {name, spec}
//     - name: hazard
//       spec: historically({emergency} -> once[0:1]{hazard_lights})
//       level: warn                  # optional: its /diagnostics level when violated
//   hazard: historically(...)        # or a plain map name -> spec
// Names must be unique; a property without a name gets "p<N>".
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "engine/checker.hpp"

namespace rvc::io {

struct PropertiesError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<engine::PropertySpec> load_properties(const std::string& path);

// The `level:` (warn or error, lower case) of the properties that give one,
// for rvc monitor's /diagnostics output. Throws as load_properties.
struct PropertyLevel {
  size_t index = 0;  // in load_properties' list
  std::string level;
  std::string name;
};
std::vector<PropertyLevel> load_property_levels(const std::string& path);

}  // namespace rvc::io
