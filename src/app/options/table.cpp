// The table of identify's and select's options (option_table.hpp): one entry per option.

#include <algorithm>
#include <array>
#include <stdexcept>

#include "app/options/setters.hpp"
#include "momentid/error.hpp"
#include "momentid/model.hpp"
#include "momentid/option_table.hpp"
#include "momentid/record_options.hpp"

namespace momentid {
namespace options {
namespace {

using V = OptionValue;
using S = OptionStage;
using C = OptionCommands;

// clang-format off
// One entry per option: flag, keyword, field, value name, kind, default, help, commands,
// stage, repeated, excludes, when empty, setter.
constexpr std::array kOptions = {
  OptionDescription{"--multipliers", "multipliers", "multipliers", "LIST", V::kMonomials,
    "automatic", "multipliers of the zero-lag equations, as for derive, e.g. \"y, v, y^3\"",
    C::kIdentify, S::kModel, false, {}, "", set_multipliers},
  OptionDescription{"--degree", "degree", "degree", "D", V::kWhole, "automatic",
    "multipliers up to this degree", C::kIdentify, S::kRecord, false, {"multipliers"}, "",
    set_degree},
  OptionDescription{"--input-hold", "input_hold", "hold", "sample|zoh", V::kChoice,
    "the file's input-hold metadata, else sample", "how the inputs were sampled", C::kBoth,
    S::kRecord, false, {}, "", set_hold},
  OptionDescription{"--batches", "batches", "batches", "B", V::kCount,
    "one per 200 samples, 100 to 1000; at least four per equation for the optimal weighting",
    "contiguous batches for the standard errors (and the optimal weighting's weights)",
    C::kBoth, S::kRecord, false, {}, "", set_batches},
  OptionDescription{"--method", "method", "method", "auto|zero-lag|lagged", V::kChoice, "auto",
    "which moment equations: lagged for measured records (unbiased under white sensor noise), "
    "zero-lag for records simulated without noise", C::kIdentify, S::kRecord, false, {}, "",
    set_method},
  OptionDescription{"--weighting", "weighting", "weighting", "auto|ls|gmm", V::kChoice, "auto",
    "ls (least squares), gmm (optimal weights, with the J test), or auto: gmm when the "
    "equations outnumber the parameters", C::kIdentify, S::kRecord, false, {}, "",
    set_weighting},
  OptionDescription{"--columns", "columns", "columns", "NAME=COLUMN,...", V::kPairs, "",
    "where a model variable is in the data; v'=COLUMN names a column of a state's derivative; "
    "a COLUMN may be a sum of columns, z''=acc_mass-acc_table",
    C::kBoth, S::kRecord, true, {}, "", set_columns},
  OptionDescription{"--input-shift", "input_shift", "input_shift", "K", V::kWhole, "0",
    "pair input row n with state row n + K (delayed measurements)", C::kBoth, S::kRecord, false,
    {}, "", set_input_shift},
  OptionDescription{"--lags", "lags", "lags", "FIRST..LAST", V::kRange, "from the data",
    "lagged moment equations at lags FIRST..LAST samples, e.g. 3..40 (the default when the data "
    "lack a state that a kinematic equation defines)", C::kBoth, S::kRecord, false,
    {"multipliers"}, "",
    set_lags},
  OptionDescription{"--instruments", "instruments", "instruments", "LIST", V::kMonomials,
    "the measured states, their powers and the inputs, within the moment budget",
    "instruments of the lagged equations, e.g. \"y, y^3\"", C::kBoth, S::kModel, false, {}, "",
    set_instruments},
  OptionDescription{"--noise", "noise", "noise", "auto|none|NAME=VARIANCE,...", V::kPairs,
    "auto", "white sensor noise on the states for the lagged equations: auto (estimated), none, "
    "or given", C::kBoth, S::kModel, false, {}, "none", set_noise},
  OptionDescription{"--dt", "dt", "dt", "H", V::kNumber, "the data's",
    "sample interval, overriding the data's: the time column is then not read", C::kBoth,
    S::kRecord, false, {}, "", set_dt},
  OptionDescription{"--fix", "fix", "fixed", "NAME=VALUE,...", V::kPairs, "",
    "parameters taken as known: their terms move to the right-hand side", C::kBoth, S::kModel,
    true, {}, "", set_fix},
  OptionDescription{"--center", "center", "center", "NAME,...|all", V::kNames, "",
    "remove the means of these channels before forming the moments: a sensor offset on a "
    "symmetric system", C::kBoth, S::kModel, true, {}, "", set_center},
  OptionDescription{"--integrate", "integrate", "integrate", "STATE,...", V::kNames, "",
    "form these states from the column of their derivative, for a record without them: "
    "integrated in the pass inside a high-pass filter on every channel", C::kBoth, S::kRecord,
    true, {}, "", set_integrate},
  OptionDescription{"--integrate-corner", "integrate_corner", "integrate_corner", "HZ",
    V::kNumber, "half the lower edge of the record's band",
    "the corner of --integrate's high-pass filter, Hz", C::kBoth, S::kRecord, false, {}, "",
    set_integrate_corner},
  OptionDescription{"--extrapolate", "extrapolate", "extrapolate", "dt", V::kSwitch, "",
    "estimate the bias of sampling from every other sample, and remove it when it exceeds its "
    "error (zero-lag equations, inputs sampled, not held)", C::kIdentify, S::kRecord, false, {},
    "", set_extrapolate},
  OptionDescription{"--refine", "refine", "refine", "", V::kSwitch, "",
    "refine the estimate by the simulation error of the model through the record's inputs "
    "(docs/refine.md), shown beside it", C::kIdentify, S::kRecord, false, {}, "", set_refine},
  OptionDescription{"--skip-rows", "skip_rows", "skip_rows", "N", V::kCount, "0",
    "lines after the header that are not data (descriptions), skipped; a units row is skipped "
    "without it", C::kBoth, S::kRecord, false, {}, "", set_skip_rows},
  OptionDescription{"--decimal", "decimal", "decimal", ".|,", V::kChoice, ".",
    "the decimal separator (with ; or blank separated fields)", C::kBoth, S::kRecord, false, {},
    "", set_decimal},
  OptionDescription{"--missing", "missing", "missing", "error|drop-row|split-run", V::kChoice,
    "error", "a missing value (empty, nan, NA): an error, a row dropped (its neighbours joined) "
    "or a new run", C::kBoth, S::kRecord, false, {}, "", set_missing},
  OptionDescription{"--names", "names", "column_names", "NAME,...", V::kNames, "",
    "names for the columns of a 2-D .npy array, in order", C::kBoth, S::kRecord, true, {}, "",
    set_names},
  OptionDescription{"--runs", "runs", "runs", "PREFIX,...", V::kNames, "",
    "runs in one .mat or HDF5 file: prefixes of each run's channels, e.g. run1/,run2/ (HDF5 "
    "groups) or a_,b_ (variables a_y, b_y)", C::kBoth, S::kRecord, true, {}, "", set_runs},
  OptionDescription{"--dt-from", "dt_from", "dt_from", "NAME", V::kText, "",
    "the sample interval from a scalar in a .mat or HDF5 file: NAME, or 1/NAME for a rate",
    C::kBoth, S::kRecord, false, {}, "", set_dt_from},
  OptionDescription{"--threads", "threads", "threads", "N", V::kCount, "0: one per core",
    "threads reading the data at once", C::kBoth, S::kRecord, false, {}, "", set_threads},
  OptionDescription{"--shard-size", "shard_size", "shard_bytes", "SIZE", V::kSize, "16M",
    "cut files into shards of about this size, read in parallel (k, M, G for powers of 1024)",
    C::kBoth, S::kRecord, false, {}, "", set_shard_size},
  OptionDescription{"--exhaustive", "exhaustive", "exhaustive", "N", V::kCount, "16",
    "score every subset up to this many candidates (at most 20), else eliminate backward",
    C::kSelect, S::kRecord, false, {}, "", set_exhaustive},
  OptionDescription{"--ranked", "ranked", "ranked", "N", V::kCount, "5",
    "the subsets the ranking shows", C::kSelect, S::kRecord, false, {}, "", set_ranked},
  OptionDescription{"--validate", "validate", "validation", "FILE", V::kRecord, "",
    "a second record: the best three subsets, each identified on DATA, simulated through its "
    "inputs and compared with it", C::kSelect, S::kRecord, false, {}, "", set_validation},
};
// clang-format on

bool takes(const OptionDescription& option, std::string_view command) {
  return option.commands == C::kBoth ||
         (option.commands == C::kIdentify ? command == "identify" : command == "select");
}

void check_exclusions(const std::vector<GivenOption>& given) {
  for (const GivenOption& a : given) {
    for (const std::string_view keyword : a.option->excludes) {
      if (keyword.empty()) continue;
      const auto b = std::find_if(given.begin(), given.end(), [&](const GivenOption& g) {
        return g.option->keyword == keyword;
      });
      if (b != given.end()) throw UsageError(a.name + " excludes " + b->name);
    }
  }
}

}  // namespace
}  // namespace options

using options::kOptions;

std::string to_string(OptionValue value) {
  static constexpr std::array kNames = {"count",  "whole",  "number",    "text",
                                        "choice", "names",  "monomials", "pairs",
                                        "range",  "switch", "size",      "record"};
  return kNames[static_cast<std::size_t>(value)];
}

std::span<const OptionDescription> option_table() { return kOptions; }

std::vector<const OptionDescription*> options_of(std::string_view command) {
  std::vector<const OptionDescription*> out;
  for (const OptionDescription& option : kOptions) {
    if (options::takes(option, command)) out.push_back(&option);
  }
  return out;
}

const OptionDescription* find_option(std::string_view keyword_or_flag) {
  for (const OptionDescription& option : kOptions) {
    if (option.keyword == keyword_or_flag || option.flag == keyword_or_flag) return &option;
  }
  return nullptr;
}

const OptionDescription* option_of_field(std::string_view field) {
  for (const OptionDescription& option : kOptions) {
    if (option.field == field) return &option;
  }
  return nullptr;
}

Model apply_options(const std::vector<GivenOption>& given, const Model& model,
                    const DataSource& source, SelectOptions& into) {
  options::check_exclusions(given);
  const auto apply = [&](OptionStage stage, const Model& against) {
    for (const OptionDescription& option : kOptions) {
      for (const GivenOption& g : given) {
        if (g.option == &option && option.stage == stage) {
          option.set(into, against, g.text, g.name);
        }
      }
    }
  };
  apply(OptionStage::kRecord, model);
  Model completed = declare_derivative_columns(model, into.identify.record, source);
  apply(OptionStage::kModel, completed);
  return completed;
}

RecordOptions record_options(const std::vector<GivenOption>& given) {
  options::check_exclusions(given);
  SelectOptions into;
  const Model none;  // the record's setters read no model
  for (const GivenOption& g : given) {
    if (g.option->stage != OptionStage::kRecord) {
      throw std::invalid_argument(std::string(g.option->flag) + " is not a record's option");
    }
    g.option->set(into, none, g.text, g.name);
  }
  return into.identify.record;
}

}  // namespace momentid
