#include "model/symbols.hpp"

#include <set>

namespace momentid {

std::string kind_with_article(SymbolKind kind) {
  return kind == SymbolKind::kInput ? std::string("an input") : "a " + std::string(kind_name(kind));
}

void SymbolTable::declare_measured(const SyntaxNode& statement) {
  for (const SyntaxNode& item : statement.children) {
    if (item.kind != SyntaxKind::kMeasuredItem) continue;
    declare(item.children.at(0), nullptr, SymbolKind::kMeasured);
    measured_targets_.push_back(&item.children.at(1));
    measured_written_.emplace_back(item.children.at(1).text);
  }
}

SymbolTable::SymbolTable(const Source& source, const Model& model)
    : source_(source),
      model_(&model),
      states_(model.states()),
      inputs_(model.inputs()),
      parameters_(model.parameters()),
      constants_(model.constants()),
      functions_(model.functions()),
      variables_(model.variables()) {
  for (std::size_t i = 0; i < model.measured_derivatives().size(); ++i) {
    const MeasuredDerivative& m = model.measured_derivatives()[i];
    measured_.push_back({m.name, SymbolKind::kMeasured, std::nullopt, m.where});
    measured_symbols_.push_back(model.measured_symbol(static_cast<int>(i)));
    measured_written_.push_back(m.written);
  }
  for (std::size_t i = 0; i < states_.size(); ++i) {
    state_symbols_.push_back(model.state_symbol(static_cast<int>(i)));
    derivative_symbols_.push_back(model.derivative_symbol(static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    input_symbols_.push_back(model.input_symbol(static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    parameter_symbols_.push_back(model.parameter_symbol(static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < functions_.size(); ++i) {
    function_symbols_.push_back(model.function_symbol(static_cast<int>(i)));
  }
  index_symbols();
}

void SymbolTable::declare_all(const SyntaxNode& statement, SymbolKind kind) {
  for (const SyntaxNode& child : statement.children) {
    const SyntaxNode* name = &child;
    const SyntaxNode* value = nullptr;
    const SyntaxNode* fixed = nullptr;
    if (child.kind == SyntaxKind::kParamItem || child.kind == SyntaxKind::kConstItem) {
      name = &child.children.at(0);
      for (const SyntaxNode& part : child.children) {
        if (part.kind == SyntaxKind::kSignedNumber) value = &part;
        if (part.kind == SyntaxKind::kFixedMark) fixed = &part;
      }
    }
    if (name->kind != SyntaxKind::kDeclaredName) continue;
    if (fixed != nullptr && value == nullptr) {
      source_.fail(*fixed, "a fixed parameter needs its value: write '" + std::string(name->text) +
                               " = VALUE fixed'");
    }
    declare(*name, value, kind, fixed != nullptr);
  }
}

void SymbolTable::declare(const SyntaxNode& name_node, const SyntaxNode* value_node,
                          SymbolKind kind, bool fixed) {
  const std::string name(name_node.text);
  static const std::set<std::string> reserved{
      "model",       "state",      "states", "input",  "inputs",   "param",     "params",
      "parameter",   "parameters", "const",  "consts", "constant", "constants", "multiplier",
      "multipliers", "dot",        "abs",    "sign",   "measured"};
  if (reserved.count(name) != 0) {
    source_.fail(name_node, "'" + name + "' is a reserved word and cannot be declared");
  }
  Declaration d{name, kind, std::nullopt, source_.where(name_node), fixed};
  if (auto [it, fresh] = first_declaration_.emplace(name, d); !fresh) {
    const Declaration& first = it->second;
    source_.fail(name_node,
                 "'" + name + "' is already declared as " + kind_with_article(first.kind) + " at " +
                     std::to_string(first.where.line) + ":" + std::to_string(first.where.column));
  }
  if (value_node != nullptr) {
    GiNaC::numeric v = 0;
    bool negative = false;
    for (const SyntaxNode& part : value_node->children) {
      if (part.kind == SyntaxKind::kMinusSign) negative = !negative;
      if (part.kind == SyntaxKind::kNumber) v = source_.number(part);
    }
    d.value = negative ? -v : v;
  }
  std::vector<Declaration>* list = nullptr;
  switch (kind) {
    case SymbolKind::kState:
      list = &states_;
      break;
    case SymbolKind::kInput:
      list = &inputs_;
      break;
    case SymbolKind::kParameter:
      list = &parameters_;
      break;
    case SymbolKind::kConstant:
      list = &constants_;
      break;
    case SymbolKind::kMeasured:
      list = &measured_;
      break;
  }
  list->push_back(std::move(d));
  const std::size_t variables = states_.size() + inputs_.size() + measured_.size();
  if (kind != SymbolKind::kConstant && kind != SymbolKind::kParameter &&
      variables > kMaxVariables) {
    source_.fail(name_node, "'" + name + "' is one variable too many: a model has at most " +
                                std::to_string(kMaxVariables) +
                                " states, inputs and measured columns in all");
  }
  if (kind == SymbolKind::kParameter && parameters_.size() > kMaxParameters) {
    source_.fail(name_node, "'" + name + "' is one parameter too many: a model has at most " +
                                std::to_string(kMaxParameters) + " parameters");
  }
}

void SymbolTable::make_symbols() {
  for (const Declaration& s : states_) {
    state_symbols_.emplace_back(s.name);
    derivative_symbols_.emplace_back(s.name + "'");
    variables_.push_back(
        {s.name, VariableKind::kState, static_cast<int>(state_symbols_.size()) - 1});
  }
  for (const Declaration& u : inputs_) {
    input_symbols_.emplace_back(u.name);
    variables_.push_back(
        {u.name, VariableKind::kInput, static_cast<int>(input_symbols_.size()) - 1});
  }
  for (const Declaration& m : measured_) {
    measured_symbols_.emplace_back(m.name);
    variables_.push_back(
        {m.name, VariableKind::kDerivative, static_cast<int>(measured_symbols_.size()) - 1});
  }
  for (const Declaration& p : parameters_) parameter_symbols_.emplace_back(p.name);
  index_symbols();
}

void SymbolTable::index_symbols() {
  declared_.clear();
  roles_.clear();
  for (auto* l : {&states_, &inputs_, &parameters_, &constants_, &measured_}) {
    for (const Declaration& x : *l) declared_[x.name] = &x;
  }
  const int n = static_cast<int>(states_.size());
  for (int i = 0; i < n; ++i) {
    roles_.emplace(state_symbols_[i], SymbolRole{SymbolRole::kVariable, i});
    roles_.emplace(derivative_symbols_[i], SymbolRole{SymbolRole::kDerivative, i});
  }
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    roles_.emplace(input_symbols_[i], SymbolRole{SymbolRole::kVariable, n + static_cast<int>(i)});
  }
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    roles_.emplace(parameter_symbols_[i], SymbolRole{SymbolRole::kParameter, static_cast<int>(i)});
  }
  const int inputs_end = n + static_cast<int>(inputs_.size());
  for (std::size_t i = 0; i < measured_.size(); ++i) {
    roles_.emplace(measured_symbols_[i],
                   SymbolRole{SymbolRole::kVariable, inputs_end + static_cast<int>(i)});
  }
  const int channels = inputs_end + static_cast<int>(measured_.size());
  for (std::size_t i = 0; i < functions_.size(); ++i) {
    roles_.emplace(function_symbols_[i],
                   SymbolRole{SymbolRole::kVariable, channels + static_cast<int>(i)});
  }
}

GiNaC::ex SymbolTable::function(const VariableFunction& f) {
  for (std::size_t i = 0; i < functions_.size(); ++i) {
    if (functions_[i].name == f.name) return function_symbols_[i];
  }
  functions_.push_back(f);
  function_symbols_.emplace_back(f.name);
  variables_.push_back(
      {f.name, VariableKind::kFunction, static_cast<int>(function_symbols_.size()) - 1});
  const int index = static_cast<int>(variables_.size()) - 1;
  roles_.emplace(function_symbols_.back(), SymbolRole{SymbolRole::kVariable, index});
  return function_symbols_.back();
}

// "declared: states y, v; inputs x; parameters c, k, eps; constants m"
std::string SymbolTable::declared_list() const {
  std::string out;
  auto add = [&](const char* what, const std::vector<Declaration>& list) {
    if (list.empty()) return;
    if (!out.empty()) out += "; ";
    out += what;
    for (std::size_t i = 0; i < list.size(); ++i) out += (i ? ", " : " ") + list[i].name;
  };
  add("states", states_);
  add("inputs", inputs_);
  add("parameters", parameters_);
  add("constants", constants_);
  add("measured columns", measured_);
  return out.empty() ? "nothing is declared" : "declared: " + out;
}

const Declaration* SymbolTable::find(const std::string& name) const {
  auto it = declared_.find(name);
  return it == declared_.end() ? nullptr : it->second;
}

const Declaration& SymbolTable::lookup(const SyntaxNode& at, const std::string& name) const {
  const Declaration* d = find(name);
  if (d == nullptr) source_.fail(at, "'" + name + "' is not declared (" + declared_list() + ")");
  return *d;
}

int SymbolTable::index_of(const Declaration& d) const {
  const std::vector<Declaration>& list = d.kind == SymbolKind::kState       ? states_
                                         : d.kind == SymbolKind::kInput     ? inputs_
                                         : d.kind == SymbolKind::kParameter ? parameters_
                                         : d.kind == SymbolKind::kMeasured  ? measured_
                                                                            : constants_;
  return static_cast<int>(&d - list.data());
}

GiNaC::ex SymbolTable::value(const SyntaxNode& at, const std::string& name) const {
  const Declaration& d = lookup(at, name);
  const int i = index_of(d);
  switch (d.kind) {
    case SymbolKind::kState:
      return state_symbols_[i];
    case SymbolKind::kInput:
      return input_symbols_[i];
    case SymbolKind::kParameter:
      return parameter_symbols_[i];
    case SymbolKind::kConstant:
      return *d.value;
    case SymbolKind::kMeasured:
      if (read_measured_) return measured_symbols_[i];
      source_.fail(at, "'" + name + "' is a measured column, which equations do not name: write " +
                           "the derivative it holds, " +
                           measured_written_[static_cast<std::size_t>(i)]);
  }
  return 0;
}

std::optional<GiNaC::ex> SymbolTable::measured_derivative(const std::string& name,
                                                          std::size_t order) const {
  const Declaration* d = find(name);
  if (!read_measured_ || d == nullptr || d->kind != SymbolKind::kState || order > 2) return {};
  int state = index_of(*d);
  if (order == 2) {
    const std::optional<Kinematic> k = model_->kinematic(state);
    if (!k || k->ratio != 1) return {};
    state = k->state;
  }
  const int column = model_->measured_derivative_of(state);
  if (column < 0) return {};
  const auto first = static_cast<int>(states_.size() + inputs_.size());
  return GiNaC::ex(measured_symbols_.at(static_cast<std::size_t>(column - first)));
}

GiNaC::ex SymbolTable::derivative(const SyntaxNode& at, const std::string& name) const {
  const Declaration& d = lookup(at, name);
  if (d.kind != SymbolKind::kState) {
    source_.fail(at, "cannot take the time derivative of " + kind_with_article(d.kind) + " '" +
                         name + "': only states have derivatives");
  }
  return derivative_symbols_[index_of(d)];
}

}  // namespace momentid
