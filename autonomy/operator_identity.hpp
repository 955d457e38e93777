#pragma once
// The operator's identity a vehicle file gives (autonomy.operator_key_file, autonomy.vehicle_id,
// autonomy.command_max_age_s) as the KILL check of every process that can stop the motors: the
// outer loop, the simulator and alight-mavlink refuse a disarm in the air unless the operator's
// own signed CMD_KILL comes with it (common/operator_auth.hpp, KillVerifier). Node side: reads
// the vehicle file and the key file.

#include <string>
#include <vector>

#include "common/operator_auth.hpp"

namespace alight::autonomy {

/// The verifier for `vehicle_file`; without an operator key file it authorises no KILL (and says
/// so in `warnings`). Throws ParamError naming the file and key for a bad key file.
KillVerifier load_kill_verifier(const std::string& vehicle_file,
                                std::vector<std::string>* warnings = nullptr);

}  // namespace alight::autonomy
