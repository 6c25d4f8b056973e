#pragma once

#include <string>

#include "momentid/data_pass.hpp"
#include "momentid/estimate.hpp"

namespace momentid {

// What `momentid identify` prints: the estimate and where it came from.
struct IdentifyReport {
  const Model* model = nullptr;
  std::string data_path;
  const DataMoments* data = nullptr;
  const Estimate* estimate = nullptr;
  bool gmm = false;  // the optimally weighted estimate is the main result
  // The moments in data->estimates, in order (moments_to_estimate of the system).
  const std::vector<Monomial>* moments = nullptr;
};

// A table (parameter, estimate, standard error, 95% interval), then the diagnostics.
std::string format_report_text(const IdentifyReport& report);
// The JSON layout documented in the README ("momentid identify").
std::string format_report_json(const IdentifyReport& report);

}  // namespace momentid
