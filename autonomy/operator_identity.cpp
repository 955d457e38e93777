#include "autonomy/operator_identity.hpp"

#include <cmath>

#include "autonomy/params.hpp"
#include "common/params.hpp"

namespace alight::autonomy {

KillVerifier load_kill_verifier(const std::string& vehicle_file,
                                std::vector<std::string>* warnings) {
  const AutonomyParams p = load_params(vehicle_file);
  const auto max_age_us = static_cast<int64_t>(std::llround(p.command_max_age_s * 1e6));
  if (p.operator_key_file.empty()) {
    if (warnings)
      warnings->push_back(vehicle_file +
                          ": autonomy.operator_key_file is empty: no KILL can stop the motors in "
                          "the air (a KILL lands instead)");
    return KillVerifier(std::nullopt, p.vehicle_id, max_age_us);
  }
  try {
    LoadedKey loaded = load_key_file(p.operator_key_file);
    if (warnings) warnings->insert(warnings->end(), loaded.warnings.begin(), loaded.warnings.end());
    return KillVerifier(std::move(loaded.key), p.vehicle_id, max_age_us);
  } catch (const KeyFileError& e) {
    throw ParamError(vehicle_file, "autonomy.operator_key_file", p.operator_key_file, e.what());
  }
}

}  // namespace alight::autonomy
