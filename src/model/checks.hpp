#pragma once
// Checks that look beyond one statement: equation labels, and the model as a whole once every
// statement is read.

#include <map>
#include <string>
#include <vector>

#include "model/syntax.hpp"
#include "momentid/model.hpp"

namespace momentid {

// The labels of the equations read so far, so that a label names one equation and a
// `multipliers` statement can only name a label that some equation has.
class EquationLabels {
 public:
  explicit EquationLabels(const Source& source) : source_(source) {}

  // Records `label`, put on the equation at line `line`; a label used before is an error.
  void add(const SyntaxNode& label, int line);
  // A `multipliers` statement's `label` must be one that add() has recorded.
  void check_known(const SyntaxNode& label) const;

 private:
  const Source& source_;
  std::map<std::string, int> lines_;
  std::vector<std::string> in_order_;  // as the equations come, for the message
};

// What makes a model unusable although each statement is fine: no state, no equation, a
// parameter that no equation contains, or equations that do not determine the derivative of
// every state. Such a problem is reported at a declaration, the first equation, or line 1.
void check_model(const Model& model, const Source& source);

}  // namespace momentid
