#pragma once

// The zero-lag path of identify(): the equations derived once, their moments read in one pass,
// solved and refined.

#include <optional>
#include <string>
#include <vector>

#include "momentid/derive.hpp"
#include "momentid/estimate.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The zero-lag moment equations of a model and what one pass over a record must read for them.
struct ZeroLagPlan {
  MomentSystem system;
  std::vector<Monomial> moments;  // the system's, as moments_to_estimate lists them
  // `moments`, then the channels' means and those the held-input correction adds.
  std::vector<Monomial> pass_moments;
  HeldInputCorrections held;
  std::vector<Monomial> rated;  // the monomials g of the rates of change E[(g)'] in `moments`
  std::string ends_unavailable;
  std::vector<std::optional<double>> fixed;  // per parameter (fixed_values)
};

// Derives the equations with the record's rates of change kept (DeriveOptions::rates) and plans
// the pass: the held-input correction's moments unless the inputs are known to be sampled; the
// record's ends are unavailable when the products of the rated monomials would outnumber the
// pass's moments.
ZeroLagPlan plan_zero_lag(const Model& model, const IdentifyOptions& options);

// The zero-lag identification into `result` (whose model is set): the plan, one pass, the
// solution, and the refinements (held input, sampling bias).
void identify_zero_lag(IdentifyResult& result, const DataSource& source,
                       const IdentifyOptions& options);

}  // namespace momentid
