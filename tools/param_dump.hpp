#pragma once
// Every parameter of a configuration file, read by the components' own loaders and printed from
// their declarations (common/param_schema.hpp): alight-params and its tests.

#include <functional>
#include <string>
#include <vector>

#include "common/param_schema.hpp"

namespace alight::tools {

/// The kinds of configuration file: vehicle (config/vehicles), scenario (config/scenarios),
/// camera (alight-camera's, config/cameras), station (the ground station's --config) and mocap
/// (config/mocap).
const std::vector<std::string>& param_file_kinds();

/// One section of a kind of file, as the component that owns it reads it.
struct ParamSection {
  struct Loaded {
    std::vector<ParamInfo> params;  ///< keys relative to the section
    std::string yaml;               ///< the section's body, indented for its depth
  };
  std::string key;  ///< dotted key in the file ("autonomy", "cameras.downward"); "" = top level
  std::string doc;
  /// Reads and validates the section of `file` through the component's loader (throws
  /// ParamError); with an empty `file`, the defaults.
  std::function<Loaded(const std::string& file)> load;
};

/// The sections of a `kind` file. A vehicle file's cameras are those `file` names (for the
/// defaults, an example `cameras.downward`).
std::vector<ParamSection> param_sections(const std::string& kind, const std::string& file);

/// `file` as the components read it (every key, defaults filled in), or the defaults of `kind`
/// when `file` is empty: YAML that loads back to the same parameters, each key preceded by its
/// meaning, constraint and unit. Paths in the file come out absolute, so the text loads back
/// from anywhere. Throws ParamError naming `file` as given.
std::string dump_params(const std::string& kind, const std::string& file);

}  // namespace alight::tools
