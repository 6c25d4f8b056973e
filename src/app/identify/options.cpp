#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <optional>
#include <span>
#include <string>

#include "momentid/error.hpp"
#include "momentid/identify.hpp"
#include "momentid/model.hpp"

namespace momentid {

namespace {

// Throws when the equations that share some free parameters have no term without one (as in
// m*v' = -c*v - k*y + b*x with m and b unknown): every moment equation of theirs then has a
// zero right-hand side, and the data determine those parameters only up to a common factor.
void check_scale(const Model& model, const std::function<bool(const Declaration&)>& known) {
  const auto& parameters = model.parameters();
  std::vector<std::size_t> group(parameters.size());
  std::iota(group.begin(), group.end(), std::size_t{0});
  const std::function<std::size_t(std::size_t)> root = [&](std::size_t p) {
    return group[p] == p ? p : group[p] = root(group[p]);
  };
  const auto free_in = [&](const Term& t) {
    return t.parameter >= 0 && !known(parameters[t.parameter]);
  };
  for (const Equation& eq : model.equations()) {
    std::optional<std::size_t> first;
    for (const Term& t : eq.terms) {
      if (!free_in(t)) continue;
      const auto p = static_cast<std::size_t>(t.parameter);
      if (first)
        group[root(p)] = root(*first);
      else
        first = p;
    }
  }
  std::vector<bool> anchored(parameters.size(), false);  // by root: some equation has a known term
  for (const Equation& eq : model.equations()) {
    const auto free_term = std::find_if(eq.terms.begin(), eq.terms.end(), free_in);
    if (free_term == eq.terms.end()) continue;
    if (!std::all_of(eq.terms.begin(), eq.terms.end(), free_in)) {
      anchored[root(static_cast<std::size_t>(free_term->parameter))] = true;
    }
  }
  for (const Equation& eq : model.equations()) {
    const auto free_term = std::find_if(eq.terms.begin(), eq.terms.end(), free_in);
    if (free_term == eq.terms.end()) continue;
    const std::size_t r = root(static_cast<std::size_t>(free_term->parameter));
    if (anchored[r]) continue;
    std::string names;
    for (std::size_t p = 0; p < parameters.size(); ++p) {
      if (root(p) == r && !known(parameters[p]))
        names += (names.empty() ? "" : ", ") + parameters[p].name;
    }
    throw ModelError(eq.where, "every term of equation " + eq.name() +
                                   " carries an unknown parameter (" + names +
                                   "), so the data determine them only up to a common factor: "
                                   "give one of them a value (a constant in the model, or " +
                                   UsageError::mention("fixed") + ")");
  }
}

}  // namespace

void IdentifyOptions::validate(const Model& model) const {
  if (batches && (*batches < kMinBatches || *batches > kMaxBatches)) {
    throw UsageError("batches", "expected a number from " + std::to_string(kMinBatches) + " to " +
                                    std::to_string(kMaxBatches) + ", found " +
                                    std::to_string(*batches));
  }
  if (degree < 0 || degree > kMaxDegree) {
    throw UsageError("degree", "expected 0 (automatic) or a number from 1 to " +
                                   std::to_string(kMaxDegree) + ", found " +
                                   std::to_string(degree));
  }
  if (input_shift < -kMaxInputShift || input_shift > kMaxInputShift) {
    throw UsageError("input_shift", "expected a number from -" + std::to_string(kMaxInputShift) +
                                        " to " + std::to_string(kMaxInputShift) + ", found " +
                                        std::to_string(input_shift));
  }
  for (const std::string& name : integrate) {
    const int v = model.variable_index(name);
    if (v < 0 || model.variables()[static_cast<std::size_t>(v)].kind != VariableKind::kState) {
      throw UsageError("integrate", "'" + name + "' is not a state of model " + model.name());
    }
  }
  if (method == Method::kZeroLag && !integrate.empty()) {
    throw UsageError("method", "the zero-lag equations do not read states formed by " +
                                   UsageError::mention("integrate"));
  }
  if (integrate_corner && !(std::isfinite(*integrate_corner) && *integrate_corner > 0)) {
    throw UsageError("integrate_corner", "expected a positive frequency in Hz");
  }
  if (method == Method::kZeroLag && (lags || instruments)) {
    throw UsageError("method", "the zero-lag equations take no lags or instruments");
  }
  const std::vector<std::string> variables = model.channel_names();
  for (const auto& [name, value] : fixed) {
    if (model.parameter_index(name) < 0) {
      throw UsageError("fixed", "'" + name + "' is not a parameter of model " + model.name());
    }
    if (!std::isfinite(value)) {
      throw UsageError("fixed", "the value of '" + name + "' must be a finite number");
    }
  }
  const auto declared_fixed = [&](const Declaration& p) { return p.fixed || fixed.count(p.name); };
  if (!model.parameters().empty() &&
      std::all_of(model.parameters().begin(), model.parameters().end(), declared_fixed)) {
    throw UsageError("fixed", "every parameter of model " + model.name() + " is fixed (by " +
                                  UsageError::mention("fixed") +
                                  " or in the model file): there is nothing to estimate");
  }
  check_scale(model, declared_fixed);
  for (const std::string& name : center) {
    if (std::find(variables.begin(), variables.end(), name) == variables.end()) {
      throw UsageError("center", "'" + name + "' is not a state or input of model " + model.name());
    }
  }
  record.validate(&model);
}

const std::vector<ParameterEstimate>& IdentifyResult::parameters() const {
  return estimate.main().parameters;
}

}  // namespace momentid
