// Parses the model language with the PEGTL grammar in grammar/ into a PEGTL-free tree
// (model/syntax.hpp) and hands it to ModelBuilder, which checks what the text means.
// This is the only translation unit that includes PEGTL.

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "error_messages.hpp"
#include "model/model_builder.hpp"
#include "model/symbols.hpp"
#include "model/syntax.hpp"
#include "model/terms.hpp"
#include "model_grammar.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/model.hpp"
#include "tao/pegtl/contrib/parse_tree.hpp"

namespace momentid {
namespace {

constexpr int kMaxNesting = 200;  // of parentheses

namespace pegtl = tao::pegtl;
namespace g = grammar;
using Node = pegtl::parse_tree::node;

// A rule the parse tree keeps, and its kind in the PEGTL-free tree.
template <typename Rule, SyntaxKind Kind>
struct KeptRule {
  using rule = Rule;
  static constexpr SyntaxKind kind = Kind;
};

// The rules the parse tree keeps, listed once for both the PEGTL selector and the conversion to
// SyntaxNode; every other rule only groups its children.
template <typename... Entries>
struct KeptRules {
  template <typename Rule>
  using selector =
      pegtl::parse_tree::selector<Rule,
                                  pegtl::parse_tree::store_content::on<typename Entries::rule...>>;

  static SyntaxKind kind_of(const Node& n) {
    SyntaxKind kind{};
    (void)((n.is_type<typename Entries::rule>() && (kind = Entries::kind, true)) || ...);
    return kind;
  }
};

// clang-format off
using ParseTreeRules = KeptRules<
    KeptRule<g::model_statement, SyntaxKind::kModelStatement>,
    KeptRule<g::model_name, SyntaxKind::kModelName>,
    KeptRule<g::string_body, SyntaxKind::kStringBody>,
    KeptRule<g::state_declaration, SyntaxKind::kStateDeclaration>,
    KeptRule<g::input_declaration, SyntaxKind::kInputDeclaration>,
    KeptRule<g::param_declaration, SyntaxKind::kParamDeclaration>,
    KeptRule<g::const_declaration, SyntaxKind::kConstDeclaration>,
    KeptRule<g::measured_statement, SyntaxKind::kMeasuredStatement>,
    KeptRule<g::measured_item, SyntaxKind::kMeasuredItem>,
    KeptRule<g::measured_target, SyntaxKind::kMeasuredTarget>,
    KeptRule<g::declared_name, SyntaxKind::kDeclaredName>,
    KeptRule<g::param_item, SyntaxKind::kParamItem>,
    KeptRule<g::fixed_mark, SyntaxKind::kFixedMark>,
    KeptRule<g::const_item, SyntaxKind::kConstItem>,
    KeptRule<g::signed_number, SyntaxKind::kSignedNumber>,
    KeptRule<g::number, SyntaxKind::kNumber>,
    KeptRule<g::label, SyntaxKind::kLabel>,
    KeptRule<g::equation, SyntaxKind::kEquation>,
    KeptRule<g::lhs, SyntaxKind::kLhs>,
    KeptRule<g::rhs, SyntaxKind::kRhs>,
    KeptRule<g::multipliers_statement, SyntaxKind::kMultipliersStatement>,
    KeptRule<g::multiplier, SyntaxKind::kMultiplier>,
    KeptRule<g::candidate_statement, SyntaxKind::kCandidateStatement>,
    KeptRule<g::candidate_name, SyntaxKind::kCandidateName>,
    KeptRule<g::library_statement, SyntaxKind::kLibraryStatement>,
    KeptRule<g::library_target, SyntaxKind::kLibraryTarget>,
    KeptRule<g::library_term, SyntaxKind::kLibraryTerm>,
    KeptRule<g::expression, SyntaxKind::kExpression>,
    KeptRule<g::term_operand, SyntaxKind::kTermOperand>,
    KeptRule<g::product, SyntaxKind::kProduct>,
    KeptRule<g::times, SyntaxKind::kTimes>,
    KeptRule<g::divide, SyntaxKind::kDivide>,
    KeptRule<g::add, SyntaxKind::kAdd>,
    KeptRule<g::subtract, SyntaxKind::kSubtract>,
    KeptRule<g::unary, SyntaxKind::kUnary>,
    KeptRule<g::operand, SyntaxKind::kOperand>,
    KeptRule<g::minus_sign, SyntaxKind::kMinusSign>,
    KeptRule<g::plus_sign, SyntaxKind::kPlusSign>,
    KeptRule<g::power, SyntaxKind::kPower>,
    KeptRule<g::exponent_operand, SyntaxKind::kExponentOperand>,
    KeptRule<g::variable, SyntaxKind::kVariable>,
    KeptRule<g::name, SyntaxKind::kName>,
    KeptRule<g::primes, SyntaxKind::kPrimes>,
    KeptRule<g::dot_call, SyntaxKind::kDotCall>,
    KeptRule<g::dot_argument, SyntaxKind::kDotArgument>,
    KeptRule<g::call, SyntaxKind::kCall>,
    KeptRule<g::parenthesized, SyntaxKind::kParenthesized>>;
// clang-format on

template <typename Rule>
using Selector = ParseTreeRules::selector<Rule>;

template <typename Rule>
using Control = pegtl::must_if<g::error_messages>::control<Rule>;

// `n` and everything under it as the meaning checks read it, without PEGTL's types.
SyntaxNode to_syntax(const Node& n) {
  const pegtl::position p = n.begin();
  SyntaxNode out{ParseTreeRules::kind_of(n), n.string_view(), p.line, p.column, {}};
  out.children.reserve(n.children.size());
  for (const auto& child : n.children) out.children.push_back(to_syntax(*child));
  return out;
}

// The top-level nodes under the root of a PEGTL parse tree, which itself matched nothing.
std::vector<SyntaxNode> top_level(const Node& root) {
  std::vector<SyntaxNode> out;
  out.reserve(root.children.size());
  for (const auto& child : root.children) out.push_back(to_syntax(*child));
  return out;
}

// Where to report a parse error. Expressions and lists may continue on the next line, so when
// something required is missing the parser has already skipped line breaks and comments; the
// error then belongs at the end of the last line with content, right after what came before.
SourceLocation error_location(std::string_view text, const std::string& file,
                              const pegtl::position& p) {
  std::size_t end = std::min(p.byte, text.size());
  bool skipped_line = false;
  while (true) {
    while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) {
      skipped_line = skipped_line || text[end - 1] == '\n';
      --end;
    }
    if (!skipped_line || end == 0) break;
    const std::size_t newline = text.rfind('\n', end - 1);
    const std::size_t start = newline == std::string_view::npos ? 0 : newline + 1;
    std::size_t content = text.find('#', start);
    if (content == std::string_view::npos || content > end) content = end;
    while (content > start && std::isblank(static_cast<unsigned char>(text[content - 1]))) {
      --content;
    }
    if (content == start) {  // a comment line or a blank line: look further up
      end = start;
      continue;
    }
    const auto line =
        static_cast<std::size_t>(std::count(text.begin(), text.begin() + start, '\n')) + 1;
    return {file, static_cast<int>(line), static_cast<int>(content - start + 1),
            line_of(text, line)};
  }
  return {file, static_cast<int>(p.line), static_cast<int>(p.column), line_of(text, p.line)};
}

// Parentheses nested too deep would exhaust the stack of the recursive parser and evaluator.
// The scan runs before parsing and stays hand-written: PEGTL's own limit (the limit_depth action
// of tao/pegtl/contrib/limit_depth.hpp) counts while parsing, so a syntax error earlier in the
// text would be reported instead, and parentheses after such an error would never be counted.
// Its message could be mapped to this one, but not the order in which errors are found, and
// grammar/README.md promises that deep nesting is refused before parsing.
void check_nesting(std::string_view text, const std::string& file) {
  int depth = 0;
  std::size_t line = 1, line_start = 0;
  bool comment = false, quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (ch == '\n') {
      ++line;
      line_start = i + 1;
      comment = quoted = false;
    } else if (comment) {
      continue;
    } else if (ch == '"') {
      quoted = !quoted;
    } else if (quoted) {
      continue;
    } else if (ch == '#') {
      comment = true;
    } else if (ch == '(' && ++depth > kMaxNesting) {
      throw ParseError(
          {file, static_cast<int>(line), static_cast<int>(i - line_start + 1), line_of(text, line)},
          "parentheses are nested more than " + std::to_string(kMaxNesting) + " deep");
    } else if (ch == ')' && depth > 0) {
      --depth;
    }
  }
}

template <typename Rule>
std::unique_ptr<Node> parse_tree(pegtl::memory_input<>& in, std::string_view text,
                                 const std::string& file) {
  check_nesting(text, file);
  try {
    return pegtl::parse_tree::parse<Rule, Selector, pegtl::nothing, Control>(in);
  } catch (const pegtl::parse_error& e) {
    const pegtl::position& p = e.positions().front();
    if (g::may_follow_line_break(e.message())) {
      throw ParseError(error_location(text, file, p), std::string(e.message()));
    }
    throw ParseError(
        {file, static_cast<int>(p.line), static_cast<int>(p.column), line_of(text, p.line)},
        std::string(e.message()));
  }
}

}  // namespace

const char* kind_name(SymbolKind kind) {
  switch (kind) {
    case SymbolKind::kState:
      return "state";
    case SymbolKind::kInput:
      return "input";
    case SymbolKind::kParameter:
      return "parameter";
    case SymbolKind::kConstant:
      return "constant";
    case SymbolKind::kMeasured:
      return "measured column";
  }
  return "";
}

int Model::measured_derivative_of(int state) const {
  for (std::size_t i = 0; i < measured_.size(); ++i) {
    if (measured_[i].state == state) {
      return static_cast<int>(states_.size() + inputs_.size() + i);
    }
  }
  return -1;
}

std::optional<Kinematic> Model::kinematic(int s) const {
  for (const Equation& eq : equations_) {
    if (eq.terms.size() != 2) continue;
    const Term* derivative = nullptr;
    const Term* state = nullptr;
    for (const Term& t : eq.terms) {
      if (t.parameter >= 0) break;
      if (t.derivative == s && t.monomial.degree() == 0) derivative = &t;
      if (t.derivative < 0 && t.monomial.degree() == 1) state = &t;
    }
    if (derivative == nullptr || state == nullptr) continue;
    const auto w = static_cast<std::size_t>(
        std::find(state->monomial.begin(), state->monomial.end(), 1) - state->monomial.begin());
    if (variables_[w].kind != VariableKind::kState) continue;
    return Kinematic{&eq, static_cast<int>(w), -state->coefficient / derivative->coefficient};
  }
  return std::nullopt;
}

int Model::integral_of(int w) const {
  for (std::size_t y = 0; y < states_.size(); ++y) {
    const std::optional<Kinematic> k = kinematic(static_cast<int>(y));
    if (k && k->state == w) return static_cast<int>(y);
  }
  return -1;
}

int Model::parameter_index(std::string_view name) const {
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (parameters_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<std::string> Model::channel_names() const {
  std::vector<std::string> out;
  for (const Variable& v : variables_) {
    if (v.channel()) out.push_back(v.name);
  }
  return out;
}

int Model::variable_index(std::string_view name) const {
  for (std::size_t v = 0; v < variables_.size(); ++v) {
    if (variables_[v].name == name) return static_cast<int>(v);
  }
  return -1;
}

Model parse_model(std::string_view text, const std::string& file) {
  const AlgebraLock lock;
  // A UTF-8 byte order mark, as some editors write, is not part of the model.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  if (text.size() > kMaxModelBytes) {
    const std::string_view kept = text.substr(0, kMaxModelBytes);
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(kept.begin(), kept.end(), '\n'));
    const std::size_t start = kept.rfind('\n') == std::string_view::npos ? 0 : kept.rfind('\n') + 1;
    throw ParseError({file, static_cast<int>(line), static_cast<int>(kMaxModelBytes - start + 1),
                      line_of(text, line)},
                     "the model goes on past " + std::to_string(kMaxModelBytes) +
                         " bytes: a model's text is at most that long");
  }
  // The parse tree's positions refer to the input's source name: it must outlive the tree.
  pegtl::memory_input in(text.data(), text.size(), file);
  std::unique_ptr<Node> root = parse_tree<g::model_file>(in, text, file);
  if (!root) throw ParseError({file, 1, 1, line_of(text, 1)}, "expected a model");
  return ModelBuilder(text, file).build(top_level(*root));
}

Model parse_model_file(const std::string& path) {
  const AlgebraLock lock;
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored)) {
    throw Error(path + ": cannot read the model file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the model file: " + std::strerror(errno));
  // One byte more than a model may have, so that a longer file (or an endless one) is refused.
  std::string text(kMaxModelBytes + 4, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return parse_model(text, path);
}

namespace {

std::vector<Monomial> parse_monomial_list(const Model& model, std::string_view text,
                                          const std::string& source, bool inputs) {
  pegtl::memory_input in(text.data(), text.size(), source);
  std::unique_ptr<Node> root = parse_tree<g::multiplier_option>(in, text, source);
  if (!root) throw ParseError({source, 1, 1, std::string(text)}, "expected multipliers");
  const std::vector<SyntaxNode> items = top_level(*root);
  const Source where(text, source);
  SymbolTable symbols(where, model);
  if (inputs) symbols.read_measured();
  const TermBuilder terms(where, symbols);
  std::vector<Monomial> out;
  for (const SyntaxNode& item : items) {
    if (item.kind != SyntaxKind::kMultiplier) continue;
    terms.add_monomial(item, out, inputs);
    if (symbols.variables().size() > model.variables().size()) {
      where.fail(item, "instrument '" + std::string(item.text) +
                           "' holds a function that no equation of the model holds: an "
                           "instrument's abs(...) and sign(...) are the model's own");
    }
  }
  return out;
}

}  // namespace

std::vector<Monomial> parse_multiplier_list(const Model& model, std::string_view text,
                                            const std::string& source) {
  const AlgebraLock lock;
  return parse_monomial_list(model, text, source, /*inputs=*/false);
}

std::vector<Monomial> parse_instrument_list(const Model& model, std::string_view text,
                                            const std::string& source) {
  const AlgebraLock lock;
  return parse_monomial_list(model, text, source, /*inputs=*/true);
}

std::string format_monomial(const Model& model, const Monomial& monomial) {
  const AlgebraLock lock;
  std::string out;
  for (std::size_t i = 0; i < monomial.size(); ++i) {
    if (monomial[i] == 0) continue;
    if (!out.empty()) out += "*";
    out += model.variables()[i].name;
    if (monomial[i] > 1) out.append("^").append(std::to_string(monomial[i]));
  }
  return out.empty() ? "1" : out;
}

GiNaC::numeric parse_exact_number(std::string_view text) {
  std::string digits;
  long scale = 0;  // power of ten
  bool fraction = false;
  std::size_t i = 0;
  for (; i < text.size() && text[i] != 'e' && text[i] != 'E'; ++i) {
    if (text[i] == '.') {
      fraction = true;
      continue;
    }
    digits += text[i];
    if (fraction) --scale;
  }
  if (i < text.size()) {
    ++i;
    bool negative = false;
    if (text[i] == '+' || text[i] == '-') negative = text[i++] == '-';
    long e = 0;
    for (; i < text.size(); ++i) e = std::min<long>(e * 10 + (text[i] - '0'), 1000000);
    scale += negative ? -e : e;
  }
  const std::size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) return 0;
  digits.erase(0, first);
  // The power of ten of the leading digit decides the range.
  const long magnitude = scale + static_cast<long>(digits.size()) - 1;
  if (magnitude > kMaxDecimalExponent || magnitude < -kMaxDecimalExponent ||
      digits.size() > static_cast<std::size_t>(kMaxDecimalExponent)) {
    throw std::out_of_range(
        "the number '" + std::string(text.substr(0, 40)) + (text.size() > 40 ? "..." : "") +
        "' is out of range (powers of ten from -" + std::to_string(kMaxDecimalExponent) + " to " +
        std::to_string(kMaxDecimalExponent) + " and at most " +
        std::to_string(kMaxDecimalExponent) + " digits are accepted)");
  }
  return GiNaC::numeric(digits.c_str()) * GiNaC::pow(GiNaC::numeric(10), GiNaC::numeric(scale));
}

}  // namespace momentid
