// Channels that are sums of columns (`--columns "z''=acc_mass-acc_table"`): DataSource::open
// reads the columns the sums need and delivers each sum as one column.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "common/decimal.hpp"
#include "data/formats.hpp"
#include "data/text.hpp"

namespace momentid {
namespace {

// Whether `text` could be a sum rather than a plain column name: it holds an operator or a
// blank (a name with blanks is still taken as a column when the record has one so named).
bool may_be_sum(std::string_view text) {
  return text.find_first_of("+-* \t'\"") != std::string_view::npos;
}

// A syntax error in a sum: what was expected, where.
struct SumSyntax {
  std::string message;
};

class SumParser {
 public:
  explicit SumParser(std::string_view text) : text_(text) {}

  ColumnSum parse() {
    ColumnSum out;
    blanks();
    double sign = 1;
    if (take('-')) {
      sign = -1;
    } else {
      take('+');
    }
    while (true) {
      out.terms.push_back(term(sign));
      blanks();
      if (at_end()) break;
      if (take('+')) {
        sign = 1;
      } else if (take('-')) {
        sign = -1;
      } else {
        expected("'+', '-' or the end");
      }
    }
    return out;
  }

 private:
  // [number *] column [* number]
  ColumnSum::Term term(double sign) {
    blanks();
    ColumnSum::Term out{sign, ""};
    if (const std::optional<double> factor = number()) {
      out.factor *= *factor;
      blanks();
      if (!take('*')) expected("'*' after the factor " + shortest_decimal(*factor));
      blanks();
    }
    out.column = column();
    blanks();
    if (take('*')) {
      blanks();
      const std::optional<double> factor = number();
      if (!factor) expected("a number after '*'");
      out.factor *= *factor;
    }
    return out;
  }

  std::optional<double> number() {
    if (at_end() || !(std::isdigit(static_cast<unsigned char>(text_[at_])) || text_[at_] == '.')) {
      return std::nullopt;
    }
    double value = 0;
    const auto [end, error] =
        std::from_chars(text_.data() + at_, text_.data() + text_.size(), value);
    if (error != std::errc{} || !std::isfinite(value)) expected("a number");
    at_ = static_cast<std::size_t>(end - text_.data());
    return value;
  }

  // A name without blanks, operators or quotes, or any name in single or double quotes.
  std::string column() {
    if (at_end()) expected("a column name");
    const char quote = text_[at_];
    if (quote == '\'' || quote == '"') {
      const std::size_t close = text_.find(quote, at_ + 1);
      if (close == std::string_view::npos || close == at_ + 1) {
        expected(std::string("a column name and a closing ") + quote);
      }
      std::string name(text_.substr(at_ + 1, close - at_ - 1));
      at_ = close + 1;
      return name;
    }
    const std::size_t end = std::min(text_.find_first_of("+-* \t'\"", at_), text_.size());
    if (end == at_ || std::isdigit(static_cast<unsigned char>(text_[at_])) || text_[at_] == '.') {
      expected("a column name (in quotes when it holds blanks or operators)");
    }
    std::string name(text_.substr(at_, end - at_));
    at_ = end;
    return name;
  }

  [[noreturn]] void expected(const std::string& what) const {
    throw SumSyntax{"expected " + what + " at character " + std::to_string(at_ + 1) + ", found " +
                    (at_end() ? "the end" : "'" + std::string(1, text_[at_]) + "'")};
  }

  void blanks() {
    while (!at_end() && (text_[at_] == ' ' || text_[at_] == '\t')) ++at_;
  }
  bool take(char c) {
    if (at_end() || text_[at_] != c) return false;
    ++at_;
    return true;
  }
  bool at_end() const { return at_ >= text_.size(); }

  std::string_view text_;
  std::size_t at_ = 0;
};

// The columns of a sum are requested under names no model variable can have.
std::string term_name(std::size_t k) { return "\x01sum term " + std::to_string(k); }

// Delivers the requested columns with each sum formed from the columns `inner` reads: output
// column c is the sum over its terms of factor * the inner column.
class SumReader final : public DataReader {
 public:
  struct Part {
    double factor;
    std::size_t column;  // in the inner reader's rows
  };
  SumReader(std::unique_ptr<DataReader> inner, std::vector<std::vector<Part>> outputs,
            std::size_t inner_width, std::vector<std::string> sums, std::string name)
      : inner_(std::move(inner)),
        outputs_(std::move(outputs)),
        inner_width_(inner_width),
        sums_(std::move(sums)),
        name_(std::move(name)) {}

  const DataMetadata& metadata() const override { return inner_->metadata(); }
  const std::vector<std::string>& columns() const override { return inner_->columns(); }
  std::map<std::string, std::string> unusable_columns() const override {
    return inner_->unusable_columns();
  }
  std::optional<double> time_step() const override { return inner_->time_step(); }
  std::size_t rows_read() const override { return inner_->rows_read(); }
  const MissingSummary& missing() const override { return inner_->missing(); }
  std::optional<double> fraction_read() const override { return inner_->fraction_read(); }
  Steps steps() const override { return inner_->steps(); }

  bool next(DataBlock& block, std::size_t max_rows) override {
    if (!inner_->next(read_, max_rows)) {
      block.rows = 0;
      block.values.clear();
      return false;
    }
    block.rows = read_.rows;
    block.run = read_.run;
    block.run_starts = read_.run_starts;
    block.zone = read_.zone;
    const std::size_t width = outputs_.size();
    block.values.resize(read_.rows * width);
    for (std::size_t r = 0; r < read_.rows; ++r) {
      const double* in = read_.values.data() + r * inner_width_;
      double* out = block.values.data() + r * width;
      for (std::size_t c = 0; c < width; ++c) {
        double value = 0;
        for (const Part& part : outputs_[c]) value += part.factor * in[part.column];
        // Finite columns whose sum is not (1e308 + 1e308) would reach the moments as inf.
        if (!std::isfinite(value) && outputs_[c].size() > 1) {
          throw Error(name_ + ": the sum " + sums_[c] + " reaches " + shortest_decimal(value) +
                      ", beyond the range of doubles, in a row whose columns are finite");
        }
        out[c] = value;
      }
    }
    return true;
  }

 private:
  std::unique_ptr<DataReader> inner_;
  std::vector<std::vector<Part>> outputs_;
  std::size_t inner_width_;
  std::vector<std::string> sums_;
  std::string name_;
  DataBlock read_;
};

}  // namespace

std::optional<ColumnSum> column_sum(const std::string& variable, const std::string& text,
                                    const std::vector<std::string>& columns,
                                    const std::string& source) {
  if (variable == "t" || !may_be_sum(text) ||
      std::find(columns.begin(), columns.end(), text) != columns.end()) {
    return std::nullopt;
  }
  const std::string item = variable + "=" + text;
  ColumnSum sum;
  try {
    sum = SumParser(text).parse();
  } catch (const SumSyntax& e) {
    throw UsageError("columns", item + ": " + source + " has no column '" + text +
                                    "', and as a sum of columns, " + e.message);
  }
  for (const ColumnSum::Term& term : sum.terms) {
    if (std::find(columns.begin(), columns.end(), term.column) == columns.end()) {
      throw UsageError("columns", item + ": " + source + " has no column '" + term.column + "'");
    }
  }
  return sum;
}

namespace data {

std::unique_ptr<DataReader> open_sums(
    const ColumnRequest& request, const std::string& name,
    const std::function<std::unique_ptr<DataReader>(const ColumnRequest&)>& open) {
  ColumnRequest plain = request;
  std::vector<std::string> candidates;
  for (auto it = plain.rename.begin(); it != plain.rename.end();) {
    if (it->first != "t" && may_be_sum(it->second)) {  // the time is always a column
      candidates.push_back(it->first);
      it = plain.rename.erase(it);
    } else {
      ++it;
    }
  }
  if (candidates.empty()) return open(request);

  // The record's columns decide: a value that names one is that column.
  std::vector<std::string> present;
  {
    ColumnRequest probe = plain;
    probe.names.clear();
    probe.min_rows = 0;
    probe.part = {};
    const std::unique_ptr<DataReader> header = open(probe);
    const std::string prefix = request.layout.runs.empty() ? "" : request.layout.runs.front();
    for (const std::string& c : header->columns()) {
      if (c.starts_with(prefix)) present.push_back(c.substr(prefix.size()));
    }
    for (const auto& [column, why] : header->unusable_columns()) {
      if (column.starts_with(prefix)) present.push_back(column.substr(prefix.size()));
    }
  }
  std::map<std::string, ColumnSum> sums;
  for (const std::string& key : candidates) {
    const std::string& text = request.rename.at(key);
    if (std::optional<ColumnSum> sum = column_sum(key, text, present, name)) {
      sums.emplace(key, std::move(*sum));
    } else {
      plain.rename.emplace(key, text);
    }
  }
  if (sums.empty()) return open(plain);

  // The inner request: the plain names, then each column a sum reads, once.
  ColumnRequest inner = plain;
  inner.names.clear();
  std::vector<std::vector<SumReader::Part>> outputs;
  std::vector<std::string> shown;
  std::map<std::string, std::size_t> term_columns;
  for (const std::string& n : request.names) {
    const auto sum = sums.find(n);
    if (sum == sums.end()) {
      outputs.push_back({{1.0, inner.names.size()}});
      shown.push_back(n);
      inner.names.push_back(n);
    } else {
      outputs.emplace_back();
      shown.push_back(request.rename.at(n));
    }
  }
  for (std::size_t c = 0; c < request.names.size(); ++c) {
    const auto sum = sums.find(request.names[c]);
    if (sum == sums.end()) continue;
    for (const ColumnSum::Term& term : sum->second.terms) {
      auto [at, fresh] = term_columns.emplace(term.column, inner.names.size());
      if (fresh) {
        const std::string slot = term_name(inner.names.size());
        inner.names.push_back(slot);
        inner.rename[slot] = term.column;
      }
      outputs[c].push_back({term.factor, at->second});
    }
  }
  const std::size_t width = inner.names.size();
  return std::make_unique<SumReader>(open(inner), std::move(outputs), width, std::move(shown),
                                     name);
}

}  // namespace data
}  // namespace momentid
