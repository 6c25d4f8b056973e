#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "momentid/identify.hpp"

// Like identify.hpp, this header does not include GiNaC.
namespace momentid {

// How to select terms (docs/cli/select.md): the record is read and the library identified as
// identify does with these options, on the lagged equations.
struct SelectOptions {
  IdentifyOptions identify;
  // Every subset of the candidates is scored up to this many candidates; beyond, backward
  // elimination from the whole library.
  std::size_t exhaustive = 16;
  // The subsets the ranking keeps, best first.
  std::size_t ranked = 5;
  // A second record: the best subsets (at most kValidated of the ranking), each identified on
  // the record selected from, are simulated through its inputs and compared with it as validate
  // does (docs/cli/select.md, "Validation on a second record"); nullopt: none.
  std::optional<DataSource> validation;

  static constexpr std::size_t kMaxExhaustive = 20;
  static constexpr std::size_t kValidated = 3;
};

// Which terms of a library the data want: the library identified from one pass, every subset of
// its candidate parameters scored on the library's fixed optimal weighting by the moment
// selection criterion J / dispersion + |S| ln T (S the candidates kept, T the sample intervals, J
// calibrated as the J test is), the difference-in-J test of each candidate at the best subset,
// the best subset on narrower lag windows of the same pass, and the chosen model identified.
struct SelectResult {
  // A subset of the library: per parameter of the model, whether it is kept (parameters that are
  // not candidates always are).
  struct Subset {
    std::vector<bool> kept;
    double criterion = 0;
    double j = 0;  // calibrated as the J test is: of mean dof for the right model
    int dof = 0;
    double pvalue = 0;  // on the J test's law (solve/selection.hpp, FixedWeighting::pvalue)
  };
  // A candidate at the chosen subset: J without it less J with it, chi-square(1) when its
  // parameter is 0.
  struct CandidateTest {
    std::string name;
    std::string terms;  // the monomials its parameter multiplies, as in "y^2*v"
    bool kept = false;
    double difference = 0;
    double pvalue = 0;
  };
  // A subset of the ranking, identified on the record selected from and simulated through the
  // validation record's inputs: per measured state, its fit (100 (1 - |y - y_sim| / |y -
  // mean(y)|)) and the root mean square of the error.
  struct Validated {
    std::size_t rank = 0;  // in `ranking`, from 0
    struct Output {
      std::string name;
      double fit = 0, rms = 0;
    };
    std::vector<Output> outputs;
    bool consistent = true;  // as validate judges the model (ValidateResult::consistent)
    std::string failed;      // why it could not be validated (its simulation blew up), or empty
  };
  // The best subset on the equations at lags first..last (the same pass and instruments).
  struct Window {
    int first_lag = 0, last_lag = 0;
    std::vector<bool> kept;
  };

  IdentifyResult library;  // the whole library, identified
  // The chosen model (chosen_model_text) identified as identify does, from a second pass.
  IdentifyResult chosen;
  std::vector<std::size_t> candidates;  // parameter indices
  bool exhaustive = true;               // every subset scored, else backward elimination
  std::size_t scored = 0;               // subsets scored
  double penalty = 0;                   // per candidate kept: ln T
  // The library's J over its degrees of freedom when its J test rejects it at 1%, else 1: the
  // criterion and the candidates' tests divide J by it.
  double dispersion = 1;
  std::vector<Subset> ranking;       // best first
  std::vector<CandidateTest> tests;  // per candidate
  std::vector<Window> windows;       // the library's window first
  std::vector<std::string> warnings;
  // Why the chosen structure is uncertain, one short reason each: the J test rejects the whole
  // library, the runner-up lies within the criterion's noise, or the chosen terms change with the
  // lag window. Any of them makes the selection doubtful (status) and has the runner-up
  // identified beside the chosen model. Candidates collinear on the library draw a warning
  // alone: the monomials of a polynomial library correlate beyond 0.995 on most records, and
  // where the data cannot choose between two of them the runner-up is close.
  std::vector<std::string> uncertain;
  // The runner-up subset (ranking[1]) identified as the chosen one is, when the structure is
  // uncertain.
  std::optional<IdentifyResult> runner_up;
  // With SelectOptions::validation: its name and the best subsets on it, best first.
  std::string validation_name;
  std::vector<Validated> validated;
};

// Identifies the library `model` (which must have candidates: a `candidate` or `library`
// statement) from `source` on the lagged equations and selects its terms. Throws UsageError
// for options that choose other equations, ModelError for a model without candidates, and what
// identify throws; Error when the library's equations cannot be weighted.
//
// Example (model_file.hpp):
//   std::shared_ptr<const Model> library = load_model("examples/select/library.mom");
//   SelectResult r = select_terms(*library, DataSource::file("record.csv"));
//   std::cout << format_text(r);
SelectResult select_terms(const Model& model, const DataSource& source,
                          const SelectOptions& options = {});

// The chosen model's status (identify.hpp), doubtful when it is ok but the structure is
// uncertain (SelectResult::uncertain).
Status status(const SelectResult& result);

// The ranking, the candidates' tests, the windows and the warnings, the selection's status with
// the runner-up's estimates beside the chosen ones when the structure is uncertain, then the
// chosen model's identify report.
std::string format_text(const SelectResult& result);
// The chosen model's identify JSON with `selected` and `dropped` (candidate names) and
// `selection` (docs/json.md, "select").
std::string format_json(const SelectResult& result);
// The chosen model as a model file: the library's equations without the dropped terms, its
// parameters valued at their estimates (the chosen model's once it is identified), for identify,
// validate and simulate.
std::string chosen_model_text(const SelectResult& result);
// The subset `kept` of the library as a model file, its parameters valued at the estimates of
// `estimated` (0 for a parameter it lacks): chosen_model_text for any subset.
std::string subset_model_text(const SelectResult& result, const std::vector<bool>& kept,
                              const IdentifyResult& estimated);

}  // namespace momentid
