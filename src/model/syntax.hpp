#pragma once
// The parse tree of a model file or of a `--multipliers` list, free of PEGTL: parser.cpp, the
// only translation unit that includes PEGTL, builds it, so that the meaning checks in
// symbols.cpp, terms.cpp, checks.cpp and model_builder.cpp compile without the grammar.

#include <ginac/ginac.h>

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "momentid/error.hpp"

namespace momentid {

// The rules of grammar/model_grammar.hpp that the parse tree keeps, one kind per rule, named
// after it. parser.cpp maps each rule to its kind.
enum class SyntaxKind {
  kModelStatement,
  kModelName,
  kStringBody,
  kStateDeclaration,
  kInputDeclaration,
  kParamDeclaration,
  kConstDeclaration,
  kMeasuredStatement,
  kMeasuredItem,
  kMeasuredTarget,
  kDeclaredName,
  kParamItem,
  kFixedMark,
  kConstItem,
  kSignedNumber,
  kNumber,
  kLabel,
  kEquation,
  kLhs,
  kRhs,
  kMultipliersStatement,
  kMultiplier,
  kCandidateStatement,
  kCandidateName,
  kLibraryStatement,
  kLibraryTarget,
  kLibraryTerm,
  kExpression,
  kTermOperand,
  kProduct,
  kTimes,
  kDivide,
  kAdd,
  kSubtract,
  kUnary,
  kOperand,
  kMinusSign,
  kPlusSign,
  kPower,
  kExponentOperand,
  kVariable,
  kName,
  kPrimes,
  kDotCall,
  kDotArgument,
  kCall,
  kParenthesized,
};

// One kept rule and what it matched. The rules the tree does not keep only group: their
// children become children of the nearest kept rule above them.
struct SyntaxNode {
  SyntaxKind kind = SyntaxKind::kExpression;
  std::string_view text;  // points into the parsed text, which must outlive the tree
  std::size_t line = 0;   // of the first character, from 1
  std::size_t column = 0;
  std::vector<SyntaxNode> children;
};

// The text of line `line` (from 1) of `source`, without its line break: shown under a message.
std::string line_of(std::string_view source, std::size_t line);

// The text a tree was parsed from and the name it goes by in messages: every meaning check
// reports through it, so that all of them use the same `file:line:col` form as a syntax error.
class Source {
 public:
  Source(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  // Where `node` starts, with the text of its line.
  SourceLocation where(const SyntaxNode& node) const;
  // Line 1, column 1: where a problem of the model as a whole is reported.
  SourceLocation start() const;
  // Reports a meaning error at `node`, as a ModelError.
  [[noreturn]] void fail(const SyntaxNode& node, const std::string& message) const;

  // The exact value of a number literal; one out of range is an error at the literal.
  GiNaC::numeric number(const SyntaxNode& node) const;

 private:
  std::string_view text_;
  std::string file_;
};

}  // namespace momentid
