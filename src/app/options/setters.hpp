#pragma once
// The setters of option_table(), one per option, and the readers of the kinds of value they
// share. Each reads the text of its option, checks it and stores it in SelectOptions, naming the
// option `name` in its messages (option_table.hpp).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "momentid/option_table.hpp"

namespace momentid::options {

// A whole number, 0 or more; count_in: one from low to high.
std::size_t count(const std::string& text, const std::string& name);
std::size_t count_in(const std::string& text, const std::string& name, std::size_t low,
                     std::size_t high);
// Names separated by commas; an empty text is none.
std::vector<std::string> names(const std::string& text);

// A setter, as OptionDescription::set takes it: (options, model, text, name).
using Setter = void(SelectOptions&, const Model&, const std::string&, const std::string&);

// The record and how a pass reads it.
Setter set_columns;
Setter set_dt;
Setter set_hold;
Setter set_input_shift;
Setter set_batches;
Setter set_lags;
Setter set_integrate;
Setter set_integrate_corner;
Setter set_skip_rows;
Setter set_decimal;
Setter set_missing;
Setter set_names;
Setter set_runs;
Setter set_dt_from;
Setter set_threads;
Setter set_shard_size;

// Against the completed model.
Setter set_instruments;
Setter set_noise;
Setter set_fix;
Setter set_center;
Setter set_multipliers;

// identify's own.
Setter set_degree;
Setter set_method;
Setter set_weighting;
Setter set_extrapolate;
Setter set_refine;

// select's own.
Setter set_exhaustive;
Setter set_ranked;
Setter set_validation;

}  // namespace momentid::options
